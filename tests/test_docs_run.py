"""Every command line and Python block of README.md and docs/*.md runs as written.

What runs: each fenced block of ``README.md`` and of every ``docs/*.md`` (found by glob, so a new page
is covered without touching this file) that is

* a Python block (```` ```python ````), run with ``exec`` in one namespace per document (a reader
  follows a page in one Python session: a later block may use names an earlier one defined), or
* a command block (no language, or ``sh``/``bash``/``console``) holding a line that starts with
  ``snncc ``: each ``snncc`` line runs through the real command (``snncc.cli.main.run``, in this
  process) and must exit 0.

A document's blocks run in order in one temporary directory, so later commands use earlier outputs,
as a user's would. The files a page takes as the user's own (``model.pt``, ``braille.nir``,
``test.npz`` ...) are small seeded fixtures (``FIXTURES``), put in place just before the first
command that names one, and only if nothing before made it.

**The not-run marker.** A block that cannot run here, or would take more than a few seconds (it needs
a board, a GPU, Rockpool, samna or Lava, trains for minutes, or runs the whole suite), carries,
directly above its opening fence (among the ``<!-- ... -->`` lines there), the visible marker

    <!-- not-run: REASON -->

with a REASON a reader can check (an empty reason fails). A marked block is still checked: every
``snncc`` line must parse with the real command (every option exists, every argument is valid),
and a ``python path/to/script.py --option`` line must name a script of the repository that has that
option. A block with no marker that fails, or a line in a block that is not a command as written
(``[--json]``, ``synth|encode``, ``...``), is a test failure: the docs must say commands a user can
paste. The ``<!-- api-example -->`` block of docs/api.md runs in tests/test_docs_api.py (with its
own checks of what it wrote) and is skipped here.

Inline ``snncc ...`` spans in prose and tables are checked too (not run): their verbs and options
exist, and their values parse (a mention may leave out required arguments; placeholders such as
``KIND`` or ``...`` are skipped).

A page that names a file of the user's that ``FIXTURES`` lacks gets a "file does not exist"
failure: add a small seeded builder for it there (or use a name it already has).
"""

from __future__ import annotations

import contextlib
import io
import functools
import re
import shlex
import shutil
import sys
import types
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
NIR = ROOT / "tests" / "data" / "nir"
COMMAND_LANGS = ("", "sh", "bash", "console", "shell")
MARKER = re.compile(r"<!--\s*not-run(?P<colon>:)?(?P<reason>.*?)-->")


def documents() -> list[Path]:
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


@dataclass
class Block:
    doc: Path
    line: int               # the opening fence's line (1-based)
    lang: str
    text: str
    comments: list[str]     # the <!-- ... --> lines directly above the fence

    @property
    def where(self) -> str:
        return f"{self.doc.relative_to(ROOT)}:{self.line}"

    def not_run(self) -> str | None:
        """The marker's reason, None without a marker; a marker without a reason fails."""
        for comment in self.comments:
            found = MARKER.search(comment)
            if found:
                reason = found.group("reason").strip()
                assert found.group("colon") and reason, f"{self.where}: a not-run marker must state its reason"
                return reason
        return None

    def command_lines(self) -> list[str]:
        """The block's command lines: continuations joined, comments and prompts removed, && split."""
        joined, lines = "", []
        for raw in self.text.splitlines():
            line = raw.rstrip()
            if line.endswith("\\"):
                joined += line[:-1] + " "
                continue
            line, joined = (joined + line).strip(), ""
            line = re.split(r"\s#\s|\s+#$", line, maxsplit=1)[0].strip() if not line.startswith("#") else ""
            line = line[2:] if line.startswith("$ ") else line
            lines.extend(part.strip() for part in line.split(" && ") if part.strip())
        return lines

    def snncc_lines(self) -> list[str]:
        return [line for line in self.command_lines() if line.startswith("snncc ")]

    @property
    def is_python(self) -> bool:
        return self.lang == "python"

    @property
    def is_commands(self) -> bool:
        return self.lang in COMMAND_LANGS and any(
            line.startswith(("snncc ", "python ", "pip ")) for line in self.command_lines())


def blocks(doc: Path, text: str | None = None) -> list[Block]:
    lines = (doc.read_text(encoding="utf-8") if text is None else text).splitlines()
    found, i = [], 0
    while i < len(lines):
        fence = re.match(r"^(```+)(\S*)\s*$", lines[i])
        if not fence:
            i += 1
            continue
        end = next(j for j in range(i + 1, len(lines)) if lines[j].startswith(fence.group(1)))
        comments, k = [], i - 1
        while k >= 0 and lines[k].strip().startswith("<!--"):
            comments.append(lines[k].strip())
            k -= 1
        found.append(Block(doc, i + 1, fence.group(2), "\n".join(lines[i + 1:end]) + "\n", comments))
        i = end + 1
    return found


# --- fixtures: the files a page takes as the user's own ----------------------------------------------

def _model(path: Path) -> None:
    """A small seeded RSNN (24 channels x 2 copies, 32 hidden, 28 classes, dt 5 ms) whose samples last
    0.1 s (20 steps), so a Jetson artefact unrolls 20 steps rather than 270."""
    import torch

    from snncc.frontends.checkpoint import save_checkpoint
    from snncc.models import SNNConfig, SpikingClassifier

    torch.manual_seed(0)
    model = SpikingClassifier(SNNConfig(n_hidden=32, n_outputs=28))
    model.reset_parameters(fwd_weight_scale=3.0, weight_scale_factor=0.2)
    save_checkpoint(model, path, {"dt": 0.005, "recording_length_s": 0.1, "note": "docs fixture"})


def _authors_weights(path: Path) -> None:
    """A weight list in the authors' th1 layout (48 inputs, 40 hidden, 28 outputs)."""
    import torch

    g = torch.Generator().manual_seed(1)
    torch.save([torch.randn(48, 40, generator=g) * 0.4, torch.randn(40, 28, generator=g) * 0.4,
                torch.randn(40, 40, generator=g) * 0.05], path)


def _th1_params(path: Path) -> None:
    from snncc_test_helpers import TH1_PARAMS

    path.write_text(TH1_PARAMS)


def _braille_dir(path: Path) -> None:
    """SYNTHETIC Braille in the published layout: 27 letters x 5 repetitions, threshold 1."""
    import snncc.api as api

    api.data_synth(out=path, repetitions=5, seed=0, thresholds="1")


def _labelled(channels: int, classes: int, steps: int):
    def make(path: Path) -> None:
        """Seeded random labelled spikes (SYNTHETIC): 16 samples x ``steps`` x ``channels``."""
        import numpy as np

        rng = np.random.default_rng(0)
        np.savez(path, inputs=(rng.random((16, steps, channels)) < 0.1).astype(np.uint8),
                 labels=np.arange(16) % classes)
    return make


def _spikes(path: Path) -> None:
    """The RSNN bundle's input: 2 samples x 20 steps x 48 (24 channels, 2 copies) spikes."""
    import numpy as np

    np.save(path, (np.random.default_rng(0).random((2, 20, 48)) < 0.1).astype(np.uint8))


def _spikes12(path: Path) -> None:
    """A NIR Braille graph's input: 2 samples x 40 steps x 12 channels of spikes."""
    import numpy as np

    np.save(path, (np.random.default_rng(0).random((2, 40, 12)) < 0.1).astype(np.uint8))


def _copy(name: str):
    return lambda path: shutil.copyfile(NIR / name, path)


FIXTURES = {
    "model.pt": _model,
    "weights.pt": _authors_weights,
    "parameters_th1.txt": _th1_params,
    "braille.nir": _copy("braille_noDelay_noBias_subtract.nir"),
    "model.nir": _copy("braille_noDelay_noBias_subtract.nir"),
    "cnn_sinabs.nir": _copy("cnn_sinabs.nir"),
    "braille": _braille_dir,
    "d.npz": _labelled(12, 7, 100),          # for braille.nir: 12 channels, 7 classes
    "inputs.npz": _labelled(12, 7, 100),
    "test.npz": _labelled(24, 27, 20),        # for model.pt: 24 channels, Braille's 27 letters
    "spikes.npy": _spikes,
    "spikes12.npy": _spikes12,
}


@pytest.fixture(scope="module")
def fixture_store(tmp_path_factory):
    """Each fixture built once, on first use; copied into a document's directory."""
    store = tmp_path_factory.mktemp("doc_fixtures")

    def provide(name: str, into: Path) -> None:
        made = store / name
        if not made.exists():
            FIXTURES[name](made)
        target = into / name
        if made.is_dir():
            shutil.copytree(made, target)
        else:
            shutil.copyfile(made, target)
    return provide


OUTPUT_FLAGS = ("-o", "--out", "--output", "--figures", "--dir", "out", "output")


def _names(text: str) -> list[str]:
    """Fixture names a command or block reads (with or without a trailing slash); a name that follows
    an output flag or keyword (``-o braille``, ``out="braille"``) is what the line writes, not a fixture."""
    words = [w for w in re.split(r"[\s\"'(),=]+", text) if w]
    written = {words[i + 1].rstrip("/") for i, w in enumerate(words[:-1]) if w in OUTPUT_FLAGS}
    return [name for name in FIXTURES if name not in written and (name in words or name + "/" in words)]


def run_snncc(argv: list[str]) -> tuple[int, str, str]:
    from snncc.cli.main import run

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = run(argv)
    return code, out.getvalue(), err.getvalue()


@functools.lru_cache(maxsize=None)
def _click_command(verb: str | None):
    """The click command of ``snncc`` with only ``verb`` registered (all verbs for None), built once per verb: the
    inline commands name the same few verbs hundreds of times."""
    import typer

    from snncc.cli.main import build_app

    return typer.main.get_command(build_app([verb] if verb else []))


def _command_of(argv: list[str]):
    return _click_command(argv[0] if argv and not argv[0].startswith("-") else None)


def parses(argv: list[str]) -> None:
    """Parse ``snncc argv`` with the real command (options and arguments checked), without running it."""
    import typer

    from snncc.cli.main import build_app

    command = _command_of(argv)
    names = []
    while hasattr(command, "commands") and argv and argv[0] in command.commands:
        names.append(argv[0])
        command, argv = command.commands[argv[0]], argv[1:]
    assert not hasattr(command, "commands"), f"'snncc {' '.join(names)}' needs a sub-command"
    if argv == ["--help"]:
        return
    command.make_context(" ".join(["snncc", *names]), list(argv))


def _not_a_command(line: str) -> str | None:
    for placeholder in ("...", "|", "[", "<"):
        if placeholder in line:
            return placeholder
    return None


def check_script_line(line: str, where: str) -> None:
    """``python path/script.py --opt ...``: the script is the repository's and declares each option."""
    words = shlex.split(line)
    if len(words) < 2 or words[1] == "-m":
        return
    script = ROOT / words[1]
    assert script.is_file(), f"{where}: {words[1]} is not a file of the repository"
    text = script.read_text(encoding="utf-8")
    for word in words[2:]:
        if word.startswith("--"):
            assert f'"{word.split("=")[0]}"' in text, f"{where}: {words[1]} has no option {word}"


def run_blocks(found: list[Block], directory: Path, namespace: dict, provide) -> int:
    """Run (or, where marked not-run, parse) each block of one document in ``directory``, in order;
    return how many lines and Python blocks ran."""
    ran = 0
    for block in found:
        if not (block.is_python or block.is_commands):
            continue
        if any("api-example" in c for c in block.comments):
            continue                      # run by tests/test_docs_api.py
        reason = block.not_run()
        if block.is_python:
            if reason is None:
                for name in _names(block.text):
                    if not (directory / name).exists():
                        provide(name, directory)
                exec(compile(block.text, block.where, "exec"), namespace)
                ran += 1
            else:
                compile(block.text, block.where, "exec")
            continue
        for line in block.command_lines():
            placeholder = _not_a_command(line) if line.startswith("snncc ") else None
            assert placeholder is None, f"{block.where}: {line!r} is not a command as written ({placeholder!r})"
            if line.startswith("python "):
                check_script_line(line, block.where)
            if not line.startswith("snncc "):
                assert reason is not None, f"{block.where}: {line!r} is not an snncc command: mark it not-run"
                continue
            argv = shlex.split(line)[1:]
            if reason is not None:
                parses(list(argv))
                continue
            for name in _names(line):
                if not (directory / name).exists():
                    provide(name, directory)
            code, out, err = run_snncc(argv)
            assert code == 0, f"{block.where}: `{line}` exited {code}:\n{err}{out[-2000:]}"
            ran += 1
    return ran


@pytest.mark.parametrize("doc", documents(), ids=lambda p: p.name)
def test_document_runs_as_written(doc, tmp_path, monkeypatch, fixture_store):
    """Every block of ``doc`` runs (or is marked not-run with a reason and parses)."""
    monkeypatch.chdir(tmp_path)
    module = types.ModuleType(f"docs_{doc.stem}")    # a real module: dataclasses look their module up
    monkeypatch.setitem(sys.modules, module.__name__, module)
    found = blocks(doc)
    ran = run_blocks(found, tmp_path, module.__dict__, fixture_store)
    runnable = [b for b in found if (b.is_python or b.is_commands) and b.not_run() is None
                and not any("api-example" in c for c in b.comments)]
    assert ran >= len(runnable)


def test_a_failing_or_unmarked_block_fails(tmp_path, monkeypatch, fixture_store):
    """The test can fail: a command that exits 2, a non-snncc line without a marker, a bad option
    in a marked block, and a placeholder are each an error naming the document line."""
    monkeypatch.chdir(tmp_path)
    doc = ROOT / "docs" / "probe.md"
    cases = {
        "```\nsnncc inspect missing.pt\n```\n": "exited 2",
        "```\npython bench/speed/run_all.py\n```\n": "mark it not-run",
        "<!-- not-run: a board -->\n```\nsnncc map x.net --no-such-option\n```\n": "No such option",
        "```\nsnncc map rsnn.net [--json]\n```\n": "not a command as written",
        "<!-- not-run: long -->\n```\npython bench/speed/run_all.py --no-such-option\n```\n": "has no option",
    }
    for text, message in cases.items():
        with pytest.raises(Exception, match=re.escape(message)):
            run_blocks(blocks(doc, text), tmp_path, {}, fixture_store)


INLINE = re.compile(r"`(snncc [^`]+)`")


def inline_commands() -> list[tuple[str, str]]:
    found = []
    for doc in documents():
        for number, text in enumerate(doc.read_text(encoding="utf-8").splitlines(), 1):
            if text.startswith("```"):
                continue
            for span in INLINE.findall(text):
                found.append((f"{doc.relative_to(ROOT)}:{number}", span))
    return found


def names_exist(argv: list[str]) -> list[str]:
    """What of a partial command ``snncc argv`` does not exist: its verbs, then each ``--option``."""
    import typer

    from snncc.cli.main import build_app

    command = _command_of(argv)
    while hasattr(command, "commands") and argv and not argv[0].startswith("-"):
        if argv[0] not in command.commands:
            return [f"no command {argv[0]!r}"]
        command, argv = command.commands[argv[0]], argv[1:]
    known = {"--help"} | {o for p in command.params for o in (*p.opts, *getattr(p, "secondary_opts", ()))}
    return [f"no option {a.split('=')[0]}" for a in argv if a.startswith("-") and a.split("=")[0] not in known]


def test_inline_commands_exist():
    """Each inline `snncc ...` of the prose and tables names commands and options that exist (a
    mention may leave out required arguments: `snncc train --device auto` is about one option)."""
    problems, checked = [], 0
    for where, span in inline_commands():
        argv = [w for w in shlex.split(span.replace("[", " ").replace("]", " "))[1:] if w not in ("...", "|")]
        if not argv or argv[0] in ("error:", "note:", "internal"):
            continue
        argv = [w.split("|")[0] for w in argv]
        missing = names_exist(argv)
        problems += [f"{where}: `{span}`: {p}" for p in missing]
        checked += 1
        if missing or _not_a_command(span) or any(re.fullmatch(r"[A-Z][A-Z_.]*", w) for w in argv):
            continue                      # a placeholder (KIND, MODEL.pt) is no value to check
        try:
            parses(list(argv))            # values too: a choice, a number, a path that must exist
        except AssertionError:
            continue                      # a mention of a command group (`snncc hpo`)
        except Exception as ex:  # noqa: BLE001 - click's usage errors; a mention may leave out arguments
            message = getattr(ex, "format_message", lambda: str(ex))()
            if not message.startswith("Missing"):
                problems.append(f"{where}: `{span}`: {message}")
    assert not problems, "\n".join(problems)
    assert checked >= 20


def test_marker_rules_are_enforced():
    """A not-run marker without a reason fails; one with a reason is read; blocks split as written."""
    text = ("<!-- not-run -->\n```\nsnncc map x.net\n```\n<!-- not-run: needs a board -->\n```\nsnncc run d/\n```\n"
            "<!-- main-command -->\n```\nsnncc a \\\n  --b 1 && snncc c   # note\n```\n")
    found = blocks(ROOT / "docs" / "probe.md", text)
    with pytest.raises(AssertionError, match="must state its reason"):
        found[0].not_run()
    assert found[1].not_run() == "needs a board"
    assert found[2].not_run() is None and found[2].snncc_lines() == ["snncc a    --b 1", "snncc c"]
    assert _not_a_command("snncc map rsnn.net [--json]") == "["
    with pytest.raises(Exception):
        parses(["compile", "model.pt", "--no-such-option"])
