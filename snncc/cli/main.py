"""Entry point of the ``snncc`` command: registers every verb and turns errors into one line.

Exit status: 0 success, 2 bad input, bad usage or an operating-system refusal (one line
``snncc: error: <file>: <field>: <rule>``), 1 internal error (a bug: one line, ``--debug`` for the
traceback), 130 interrupted. ``--debug`` anywhere on the command line shows tracebacks instead.
The line has exactly three parts (README, "errors"): a refusal without a file names the command
(``command_path``: ``snncc compile``), file and field are escaped onto one line
(``snncc.errors.one_line``); libraries' warnings are silenced unless ``--debug``.

Each command declares which of its parameters are inputs and which outputs
(``snncc.cli.paths.declares_paths``); while it runs, no output may be written over one of its inputs
(``snncc.atomic.protecting``).
"""

from __future__ import annotations

import errno
import os
import re
import signal
import sys
import warnings

# numpy asks the kernel for transparent huge pages on every large array (read once, when numpy is first imported).
# Where the kernel then compacts memory to find them (THP defrag "madvise", a common default), a command that makes
# many large temporaries spends seconds of system time in it: compiling a 13-million-synapse network for Loihi
# took 2.6-3.1 s of system CPU with them and 1.9-2.0 s without, the user time 0.2 s longer, other commands
# unchanged (bench/speed/README.md). A value the user set is kept.
os.environ.setdefault("NUMPY_MADVISE_HUGEPAGE", "0")

# Each module registers its verb(s) on the typer app when imported; they import only typer,
# rich and the standard library at module level, so ``snncc --help`` starts at once.
VERB_MODULES = (
    "compile_cmd", "inspect_cmd", "emulate_cmd", "check_cmd", "compare_cmd", "map_cmd", "report_cmd", "export_cmd",
    "run_cmd", "data_cmd", "train_cmd", "bench_cmd", "analyse_cmd", "hpo_cmd",
)
INTERRUPTED = "snncc: interrupted; no partial output was left behind"


def _say(line: str) -> None:
    print(line, file=sys.stderr)


def build_app(args: list[str] | None = None):
    """The typer app with the verb ``args`` invoke registered (every verb when ``args`` names none,
    as for ``snncc --help`` or a mistyped verb): building only one keeps every command's start short."""
    import importlib

    from snncc.cli.app import app

    verb = next((a for a in args or () if not a.startswith("-")), None)
    module = f"{verb}_cmd"
    for name in (module,) if module in VERB_MODULES else VERB_MODULES:
        importlib.import_module(f"snncc.cli.{name}")
    return app


def command_path(args: list[str]) -> str:
    """The command ``args`` invoke, as typed up to its last verb: ``snncc compile``, ``snncc hpo
    run``; ``snncc`` when the first word is no verb. It is the ``<file>`` part of a refusal that
    concerns the command line itself (an option's value, an unknown verb), not a file."""
    try:
        import typer

        from snncc.cli.app import app

        command = typer.main.get_command(app)
    except Exception:  # the app itself failed to build: name the program
        return "snncc"
    words = ["snncc"]
    for arg in args:
        if arg.startswith("-"):
            continue
        verbs = getattr(command, "commands", None) or {}
        if arg not in verbs:
            break
        words.append(arg)
        command = verbs[arg]
    return " ".join(words)


def _refusal(rule: str, *, file: str | None, field: str | None, args: list[str]) -> str:
    """One ``<file>: <field>: <rule>`` line; a refusal without a file names the command."""
    from snncc.errors import SnnccError

    file = file if file else command_path(args)
    return SnnccError(rule, file=file, field=field or ("usage" if file.startswith("snncc") else "contents")).line()


def _usage_line(ex, args: list[str]) -> str:
    """``<command>: <option or argument>: <message>`` from a (typer-bundled or real) click usage error."""
    ctx = getattr(ex, "ctx", None)
    where = ctx.command_path if ctx is not None and getattr(ctx, "command_path", None) else None
    param = getattr(ex, "param", None)
    message = " ".join(ex.format_message().split())
    field = None
    if param is not None:
        opts = getattr(param, "opts", None) or []
        field = (opts[0] if opts and opts[0].startswith("-") else
                 (getattr(param, "human_readable_name", None) or getattr(param, "name", None)))
    field = field or getattr(ex, "option_name", None)
    unknown = re.match(r"No such command '([^']*)'\.?\s*(.*)", message)
    if field is None and unknown:
        field = unknown.group(1)
        hint = unknown.group(2).strip()
        message = "no such command" + (f" ({hint[0].lower() + hint[1:]})" if hint else "; snncc --help lists them")
    return _refusal(message or "bad usage (see --help)", file=where, field=field, args=args)


def _os_error_line(ex: OSError, args: list[str]) -> str:
    code = errno.errorcode.get(ex.errno or 0, "OSError")
    reason = (ex.strerror or str(ex)).rstrip(".")
    return _refusal(reason.lower(), file=None if ex.filename is None else os.fsdecode(ex.filename), field=code,
                    args=args)


def _caused_by_interrupt(ex: BaseException) -> bool:
    """True if a KeyboardInterrupt is anywhere in ``ex``'s chain of causes and contexts."""
    seen: set[int] = set()
    while ex is not None and id(ex) not in seen:
        if isinstance(ex, KeyboardInterrupt):
            return True
        seen.add(id(ex))
        ex = ex.__cause__ or ex.__context__
    return False


def _dispatch(args: list[str], debug: bool) -> int:
    import typer

    from snncc.errors import InternalError, SnnccError

    # typer >= 0.29 bundles its own click, older typer re-exports the real one; either way usage
    # errors derive from the ClickException behind typer.BadParameter (no direct click import).
    click_exception = next(c for c in typer.BadParameter.__mro__ if c.__name__ == "ClickException")
    try:
        app = build_app(args)
        with warnings.catch_warnings():
            if not debug:   # libraries' warnings never reach stderr (bad input they signal is refused)
                warnings.simplefilter("ignore")
            result = app(args=args, prog_name="snncc", standalone_mode=False)
        code = result if isinstance(result, int) else 0
        if code == 130:  # typer >= 0.29 turns Ctrl-C inside a command into a silent Exit(130)
            _say(INTERRUPTED)
        return code
    except SnnccError as err:
        if debug:
            raise
        _say(f"snncc: error: {_refusal(err.rule, file=err.file, field=err.field, args=args)}")
        return 2
    except typer.Exit as ex:
        if ex.exit_code == 130:
            _say(INTERRUPTED)
        return ex.exit_code
    except typer.Abort:
        _say(INTERRUPTED)
        return 130
    except click_exception as ex:
        if debug:
            raise
        if type(ex).__name__ == "NoArgsIsHelpError":  # bare ``snncc`` or ``snncc data``: the help
            _say(ex.format_message())
            return 2
        _say(f"snncc: error: {_usage_line(ex, args)}")
        return 2
    except OSError as ex:
        if debug:
            raise
        _say(f"snncc: error: {_os_error_line(ex, args)}")
        return 2
    except InternalError as ex:   # a check of snncc's own work failed: a bug, not the input's fault
        if debug:
            raise
        _say(f"snncc: internal error: {ex.line()} (a bug in snncc; rerun with --debug for the traceback)")
        return 1
    except MemoryError:
        if debug:
            raise
        _say("snncc: error: " + _refusal("this input needs more memory than the machine has; use a smaller batch or "
                                         "input", file=None, field="memory", args=args))
        return 2
    except Exception as ex:  # the last line of defence: never a traceback without --debug
        if _caused_by_interrupt(ex):   # a library turned Ctrl-C into its own error (e.g. an ImportError)
            _say(INTERRUPTED)
            return 130
        if debug:
            raise
        first = str(ex).strip().splitlines()[0] if str(ex).strip() else ""
        _say(f"snncc: internal error: {type(ex).__name__}: {first} (rerun with --debug for the traceback)")
        return 1


def run(argv: list[str] | None = None) -> int:
    """Run the CLI; return (and, called without ``argv``, exit with) its status."""
    try:
        args = list(sys.argv[1:] if argv is None else argv)
        debug = "--debug" in args
        if debug:
            args = [a for a in args if a != "--debug"]
        code = _dispatch(args, debug)
    except KeyboardInterrupt:
        _say(INTERRUPTED)
        code = 130
    if argv is None:
        # The work is done: a Ctrl-C during the interpreter's own teardown (where Python restores the
        # default SIGINT action, which would kill the process silently) must not change the status.
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        sys.exit(code)
    return code


if __name__ == "__main__":
    run()
