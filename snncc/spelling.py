"""One message, two spellings: the command line's options (``--dt``) and snncc.api's keywords (``dt=``).

Library code writes its messages as the ``snncc`` command reads them (``pass --dt``, ``--time-steps:
must be >= 1``); ``python_spelling`` rewrites such a line for a caller of ``snncc.api``:

    --time-steps: ...     ->  time_steps: ...        (an option named as the field)
    pass --dt             ->  pass dt=               (an option named in the text)
    --reset=subtract      ->  reset='subtract'       (an option with its value; numbers stay bare)
    --set tau_mem=0.05    ->  overrides=['tau_mem=0.05']   (a repeatable KEY=VALUE option)

An option is renamed where the keyword differs from the flag (``KEYWORDS``): ``-o`` is
``output=``, ``--bin`` ``bin_ms=``, ``--set`` ``overrides=``, ...; any other ``--x-y`` is ``x_y=``.
"""

from __future__ import annotations

import re

KEYWORDS = {"-o": "output", "--bin": "bin_ms", "--from": "prefer", "--dir": "workdir", "--range": "ranges",
            "--set": "overrides"}
LIST_OPTIONS = ("--set", "--range")          # repeatable KEY=VALUE options: a list of strings in Python

_FLAG = re.compile(r"(?<![\w-])(?P<flag>--[a-z][a-z0-9-]*|-o)(?![\w-])"
                   r"(?:(?P<eq>=)(?P<value>[^\s,;:()]+)|(?P<colon>(?=:))|(?P<item> [A-Za-z_][\w.]*=[^\s,;()]*?(?=[\s,;()]|:\s|:$|$)))?")


def keyword(flag: str) -> str:
    """The snncc.api keyword of a command-line option: ``--time-steps`` -> ``time_steps``."""
    return KEYWORDS.get(flag, flag.lstrip("-").replace("-", "_"))


def _value(text: str) -> str:
    try:
        float(text)
        return text
    except ValueError:
        return repr(text)


def _python(match: re.Match) -> str:
    flag, name = match["flag"], keyword(match["flag"])
    if match["eq"]:
        return f"{name}={_value(match['value'])}"
    if match["item"] and flag in LIST_OPTIONS:
        return f"{name}=[{match['item'].strip()!r}]"
    if match["colon"] is not None:
        return name                          # ``--dt: ...``: the option is the field
    return f"{name}=" + (match["item"] or "")


def python_spelling(line: str) -> str:
    """``line`` with every command-line option written as the snncc.api keyword argument."""
    return _FLAG.sub(_python, line)
