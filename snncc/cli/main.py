"""Entry point of the ``snncc`` command: registers every verb and turns errors into one line.

Exit status: 0 success, 2 bad input (one line ``snncc: error: file: field: rule``), 1 internal
error, 130 interrupted. ``--debug`` anywhere on the command line shows tracebacks instead.
"""

from __future__ import annotations

import sys

import typer

from snncc.cli.app import app
from snncc.errors import SnnccError

# Each module registers its verb(s) on ``app`` when imported.
from snncc.cli import (  # noqa: E402,F401  (imported for their registrations)
    compile_cmd,
    inspect_cmd,
    emulate_cmd,
    check_cmd,
    map_cmd,
    report_cmd,
    export_cmd,
    run_cmd,
    data_cmd,
    train_cmd,
    bench_cmd,
    hpo_cmd,
)


# typer >= 0.29 bundles its own click; older typer re-exports the real one. Either way its usage
# errors derive from the ClickException found behind typer.BadParameter, so no click import.
_CLICK_EXCEPTION = next(c for c in typer.BadParameter.__mro__ if c.__name__ == "ClickException")


def _say(line: str) -> None:
    print(line, file=sys.stderr)


def run(argv: list[str] | None = None) -> int:
    """Run the CLI; return (and exit with) its status."""
    args = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in args
    if debug:
        args = [a for a in args if a != "--debug"]
    try:
        result = app(args=args, prog_name="snncc", standalone_mode=False)
        code = result if isinstance(result, int) else 0
    except SnnccError as err:
        if debug:
            raise
        _say(f"snncc: error: {err.line()}")
        code = 2
    except typer.Exit as ex:
        code = ex.exit_code
    except typer.Abort:
        _say("snncc: aborted")
        code = 130
    except _CLICK_EXCEPTION as ex:
        if debug:
            raise
        _say(f"snncc: error: {ex.format_message()}")
        code = ex.exit_code
    except KeyboardInterrupt:
        _say("snncc: interrupted; no partial output was left behind")
        code = 130
    except Exception as ex:  # the last line of defence: never a traceback without --debug
        if debug:
            raise
        first = str(ex).strip().splitlines()[0] if str(ex).strip() else ""
        _say(f"snncc: internal error: {type(ex).__name__}: {first} (rerun with --debug for the traceback)")
        code = 1
    if argv is None:
        sys.exit(code)
    return code


if __name__ == "__main__":
    run()
