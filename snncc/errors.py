"""The one error type users see: which file, which field, which rule."""

from __future__ import annotations

import unicodedata


def one_line(text: str, *, name: bool = False) -> str:
    """``text`` printable on one line: control and format characters (a newline, ESC, a bidi
    override, an undecodable byte of a file name) as backslash escapes (``\\n``, ``\\x1b``,
    ``\\u202e``, ``\\udcff``); for a ``name`` (a file or field part of an error line) also ``": "`` as
    ``":\\x20"``, so that the line splits into exactly three parts at ``": "``."""
    out = []
    for ch in str(text):
        if unicodedata.category(ch) in ("Cc", "Cf", "Cs", "Zl", "Zp"):
            out.append({"\n": "\\n", "\r": "\\r", "\t": "\\t"}.get(ch) or
                       (f"\\x{ord(ch):02x}" if ord(ch) < 0x100 else f"\\u{ord(ch):04x}"))
        else:
            out.append(ch)
    text = "".join(out)
    return text.replace(": ", ":\\x20") if name else text


class SnnccError(Exception):
    """A user-facing error rendered as one line: ``file: field: rule``.

    ``file`` is the input or output concerned (may be None), ``field`` the part of it that is
    wrong (a key, a node, a dataset path), ``rule`` what was expected.
    """

    def __init__(self, rule: str, *, file: str | None = None, field: str | None = None):
        self.rule = rule
        self.file = None if file is None else str(file)
        self.field = field
        super().__init__(self.line())

    def line(self) -> str:
        """``file: field: rule`` (the parts given), each on one line (``one_line``): the line the ``snncc``
        command prints, options spelt as on its command line (``--dt``)."""
        parts = [one_line(p, name=True) for p in (self.file, self.field) if p]
        return ": ".join(parts + [one_line(self.rule)])

    def __str__(self) -> str:
        """The same line for a caller of ``snncc.api``: options as keyword arguments (``dt=``;
        ``snncc.spelling``). ``line()`` keeps the command line's spelling."""
        from snncc.spelling import python_spelling

        return python_spelling(self.line())

    def with_file(self, file: str) -> "SnnccError":
        """The same error, attributed to ``file`` if it names none yet."""
        if self.file is None:
            self.file = str(file)
            self.args = (self.line(),)
        return self


class InternalError(Exception):
    """A broken internal invariant: a bug in snncc, never a fault of the user's input.

    Raised where snncc checks its own work (an artefact against the IR reference, a map against the
    chip's limits it was built to respect). The CLI prints one line ``snncc: internal error: <field>:
    <what>`` and exits 1. Deliberately not a ``SnnccError``: no handler meant for bad input (a scale
    rule left out, a candidate refused) can catch it and pass it off as the input's fault.
    """

    def __init__(self, what: str, *, field: str | None = None):
        self.what = what
        self.field = field
        super().__init__(self.line())

    def line(self) -> str:
        return ": ".join([p for p in (self.field,) if p] + [self.what])
