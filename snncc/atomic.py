"""Output that never loses a file: atomic writes, guarded destinations, crash-safe replacement.

Rules every snncc writer follows (files through :func:`atomic_path`, directories through
:func:`atomic_dir`):

* the new content is written to a hidden sibling ``.NAME.PID.XXXX.part`` and renamed into place
  only once complete, so a crash, an error, a full disk or Ctrl-C never leaves a half-written
  output at the destination;
* a destination that resolves (after symlinks) to an input of the running command, a directory
  that contains one, or a path inside an artefact directory the command reads (:func:`seal_directory`)
  is refused (:func:`protecting` declares the inputs; a file the command reads from inside an input
  directory, such as a data set's pickles, becomes one as it is read: :func:`record_input`);
* ``.``/``..``, the current directory or one of its parents, and an existing directory named as a
  file output are refused; an existing device or pipe (``-o /dev/null``) is written through, never
  replaced;
* an existing directory is replaced only if the caller recognises it as its own earlier output
  (``replaceable``); the swap is one atomic ``renameat2(RENAME_EXCHANGE)`` where the kernel has it,
  so a kill at any moment leaves either the old or the new directory complete at the path;
* leftovers of killed snncc runs (``.part``/``.old`` siblings whose process is gone) are cleaned on
  the next write to the same destination; an ``.old`` directory left by a kill between the two
  renames of the fallback swap is first put back in place.
"""

from __future__ import annotations

import contextlib
import contextvars
import ctypes
import errno
import hashlib
import os
import re
import shutil
import stat
import tempfile
from pathlib import Path
from typing import Callable, Iterable, Iterator

from snncc.errors import SnnccError

_PROTECTED: contextvars.ContextVar[tuple[Path, ...]] = contextvars.ContextVar("snncc_protected", default=())
# files read so far by the command inside its outermost ``protecting`` block (None: outside any)
_READ: contextvars.ContextVar[list[Path] | None] = contextvars.ContextVar("snncc_read", default=None)
# artefact directories the running command reads (sealed: no output may be written inside them)
_SEALED: contextvars.ContextVar[list[Path] | None] = contextvars.ContextVar("snncc_sealed", default=None)
_LEFTOVER = re.compile(r"^\.(?P<name>.+)\.(?P<pid>\d+)\.[^.]*\.(?P<kind>part|old)$")


def _default_mode(base: int) -> int:
    """``base`` minus the process umask: the mode ``open``/``mkdir`` would have given."""
    mask = os.umask(0)
    os.umask(mask)
    return base & ~mask


@contextlib.contextmanager
def protecting(paths: Iterable[str | os.PathLike]) -> Iterator[None]:
    """Within the block, no atomic write may replace any of ``paths`` (the command's inputs), nor any
    file :func:`record_input` reports as read within it."""
    resolved = tuple(Path(p).resolve() for p in paths)
    token = _PROTECTED.set(_PROTECTED.get() + resolved)
    read_token = _READ.set([]) if _READ.get() is None else None
    sealed_token = _SEALED.set([]) if _SEALED.get() is None else None
    try:
        yield
    finally:
        if sealed_token is not None:
            _SEALED.reset(sealed_token)
        if read_token is not None:
            _READ.reset(read_token)
        _PROTECTED.reset(token)


def record_input(path: str | os.PathLike) -> None:
    """``path`` was read by the running command (found inside an input it was given, e.g. a data
    set's files in a directory): until its outermost ``protecting`` block ends, no output may replace
    it. Outside any such block (a library call) nothing is recorded."""
    read = _READ.get()
    if read is not None:
        read.append(Path(path).resolve())


def seal_directory(path: str | os.PathLike) -> None:
    """``path`` is an artefact directory the running command reads: until its outermost ``protecting`` block
    ends, no output may be written inside it -- not over one of its files, nor beside them (a data set's
    directory, which commands may write into, is not sealed). Outside any such block nothing is recorded."""
    sealed = _SEALED.get()
    if sealed is not None:
        sealed.append(Path(path).resolve())


def _inputs() -> tuple[Path, ...]:
    return _PROTECTED.get() + tuple(_READ.get() or ())


def check_destination(dest: str | os.PathLike, *, directory: bool = False) -> Path:
    """``dest`` as a path, after refusing one that would destroy an input or name a working directory."""
    dest = Path(dest)
    shown = str(dest)
    if dest.name in ("", ".", ".."):
        raise SnnccError("names a directory ('.' or '..'), not a new output; give a name", file=shown, field="output")
    resolved = dest.resolve()
    cwd = Path.cwd().resolve()
    if resolved == cwd or resolved in cwd.parents:
        raise SnnccError("is the current directory or one of its parents; give a new output name", file=shown,
                         field="output")
    inputs = _inputs()
    if resolved in inputs:
        raise SnnccError("is an input of this command; writing the output there would destroy it",
                         file=shown, field="output")
    for sealed in _SEALED.get() or ():
        if sealed in resolved.parents:
            raise SnnccError(f"lies inside an artefact this command reads ({sealed}); an output there would change "
                             "that artefact: write it elsewhere", file=shown, field="output")
    for protected in inputs:
        if directory and resolved in protected.parents:
            raise SnnccError(f"contains an input of this command ({protected}); replacing it would delete that input",
                             file=shown, field="output")
    return dest


def _pid_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        with contextlib.suppress(FileNotFoundError):
            path.unlink()


def clean_leftovers(dest: Path) -> None:
    """Remove ``.part``/``.old`` siblings of ``dest`` left by snncc processes that no longer run.

    If ``dest`` itself is missing and a dead run's ``.old`` copy exists, that copy is the last
    complete output (a kill fell between the two renames of the fallback swap): it is put back.
    """
    parent = dest.parent
    if not parent.is_dir():
        return
    for entry in parent.iterdir():
        match = _LEFTOVER.match(entry.name)
        if not match or match["name"] != dest.name or _pid_alive(int(match["pid"])):
            continue
        if match["kind"] == "old" and not os.path.lexists(dest):
            os.rename(entry, dest)
            continue
        _remove(entry)


def _is_device_or_pipe(path: Path) -> bool:
    try:
        mode = path.stat().st_mode
    except OSError:
        return False
    return stat.S_ISCHR(mode) or stat.S_ISBLK(mode) or stat.S_ISFIFO(mode) or stat.S_ISSOCK(mode)


def _refuse_kind(dest: Path, directory: bool) -> None:
    check_destination(dest, directory=directory)
    if not directory and dest.is_dir():
        raise SnnccError("is a directory; this output is a file, give a file name", file=str(dest), field="output")
    if directory and dest.exists() and not dest.is_dir():
        raise SnnccError("this output is a directory, and a file of that name exists", file=str(dest), field="output")


def _prepare(dest: Path, directory: bool) -> None:
    _refuse_kind(dest, directory)
    dest.parent.mkdir(parents=True, exist_ok=True)
    clean_leftovers(dest)


def _refuse_unreplaceable(dest: Path, replaceable: Callable[[Path], str | None] | None) -> None:
    """The one-line refusal of an existing directory ``dest`` unless ``replaceable(dest)`` returns None."""
    why = "snncc replaces only a directory it wrote itself" if replaceable is None else replaceable(dest)
    if why is not None:
        raise SnnccError(f"exists and is not replaceable: {why}; choose a new name or remove it yourself",
                         file=str(dest), field="output")


def preflight(dest: str | os.PathLike, *, directory: bool = False,
              replaceable: Callable[[Path], str | None] | None = None) -> None:
    """Before long work, the refusals an atomic write to ``dest`` would meet at its end: an input of
    the command, ``.``/``..``, the wrong kind (a directory for a file), an existing directory that
    ``replaceable`` refuses (``atomic_dir``'s rule; not asked without it), and a directory where
    nothing can be written (read-only, no permission: probed by creating and removing a hidden
    ``.part`` file in the nearest existing directory). A full disk shows only when writing, where
    the atomic write keeps the old file."""
    dest = Path(dest)
    if _is_device_or_pipe(dest):
        check_destination(dest)
        return
    _refuse_kind(dest, directory)
    if directory and replaceable is not None and dest.is_dir():
        _refuse_unreplaceable(dest, replaceable)
    parent = dest.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if not parent.is_dir():
        raise SnnccError(f"{parent} is not a directory", file=str(dest), field="output")
    try:
        fd, probe = tempfile.mkstemp(prefix=f".{dest.name}.{os.getpid()}.", suffix=".part", dir=parent)
    except OSError as ex:
        raise OSError(ex.errno, ex.strerror, str(dest)) from None
    os.close(fd)
    os.unlink(probe)


@contextlib.contextmanager
def atomic_path(dest: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``dest``; rename it to ``dest`` if the block succeeds."""
    dest = Path(dest)
    if _is_device_or_pipe(dest):   # e.g. -o /dev/null: write through it, never replace the node
        check_destination(dest)
        with tempfile.TemporaryDirectory(prefix="snncc-") as scratch:
            tmp_path = Path(scratch) / dest.name
            yield tmp_path
            with open(tmp_path, "rb") as src, open(dest, "wb") as out:
                shutil.copyfileobj(src, out)
        return
    _prepare(dest, directory=False)
    fd, tmp = tempfile.mkstemp(prefix=f".{dest.name}.{os.getpid()}.", suffix=".part", dir=dest.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        if tmp_path.exists():
            os.chmod(tmp_path, _default_mode(0o666))  # mkstemp makes 0600; give a plain file's mode
        os.replace(tmp_path, dest)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp_path.unlink()
        raise


_RENAME_EXCHANGE = 2
_AT_FDCWD = -100


def exchange(a: Path, b: Path) -> bool:
    """Atomically swap two existing paths (Linux ``renameat2(RENAME_EXCHANGE)``); False if unsupported."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):
        return False
    renameat2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    if renameat2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.ENOSYS, errno.EINVAL, errno.ENOTSUP):
        return False  # kernel or file system without the exchange flag: the caller falls back
    raise OSError(err, os.strerror(err), str(b))


def _replace_directory(new: Path, dest: Path, swap: Callable[[Path, Path], bool]) -> None:
    """Put the complete directory ``new`` at ``dest`` (which exists), then delete the old one."""
    if swap(new, dest):
        shutil.rmtree(new, ignore_errors=True)  # ``new`` now holds the old directory
        return
    old = dest.with_name(f".{dest.name}.{os.getpid()}.x.old")
    os.rename(dest, old)    # a kill here leaves the old copy at .old: clean_leftovers puts it back
    os.rename(new, dest)
    shutil.rmtree(old, ignore_errors=True)


def foreign_entries(directory: Path, ours: Iterable[str]) -> str | None:
    """Why ``directory`` (an earlier artefact) may not be replaced, or None: an entry whose name is not
    among ``ours`` is a user's file; one of our names that is not a regular file (a directory, symlink
    or device) is a user's too, since snncc writes only regular files there."""
    ours = set(ours)
    entries = list(directory.iterdir())
    foreign = sorted(p.name for p in entries if p.name not in ours)
    if foreign:
        return f"it holds files snncc did not write ({', '.join(foreign[:3])}{', ...' if len(foreign) > 3 else ''})"
    odd = sorted(p.name for p in entries if p.is_symlink() or not p.is_file())
    if odd:
        return (f"{', '.join(odd[:3])}{', ...' if len(odd) > 3 else ''} is not a regular file "
                "(snncc writes only regular files there)")
    return None


@contextlib.contextmanager
def atomic_dir(dest: str | os.PathLike, replaceable: Callable[[Path], str | None] | None = None,
               swap: Callable[[Path, Path], bool] = exchange) -> Iterator[Path]:
    """Yield an empty temporary directory beside ``dest``; it becomes ``dest`` if the block succeeds.

    An existing ``dest`` is replaced only if ``replaceable(dest)`` returns None (it is the caller's
    own earlier output); otherwise the string it returns is the reason for refusing. Without
    ``replaceable`` an existing directory is always refused.
    """
    dest = Path(dest)
    _prepare(dest, directory=True)
    if dest.exists():
        _refuse_unreplaceable(dest, replaceable)
    tmp = Path(tempfile.mkdtemp(prefix=f".{dest.name}.{os.getpid()}.", suffix=".part", dir=dest.parent))
    try:
        yield tmp
        os.chmod(tmp, _default_mode(0o777))
        if dest.exists():
            _replace_directory(tmp, dest, swap)
        else:
            os.rename(tmp, dest)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def write_bytes_atomic(dest: str | os.PathLike, data: bytes) -> None:
    with atomic_path(dest) as tmp:
        tmp.write_bytes(data)


def write_text_atomic(dest: str | os.PathLike, text: str) -> None:
    write_bytes_atomic(dest, text.encode("utf-8"))


def file_sha256(path: str | os.PathLike) -> str:
    """Hex SHA-256 of a file's bytes (the 'source model hash' every artefact records)."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def write_npz_atomic(dest: str | os.PathLike, arrays: dict, compresslevel: int = 1) -> None:
    """``arrays`` as an .npz (a zip of .npy members, deflated: what ``numpy.savez_compressed``
    writes, read by ``numpy.load``) at zlib level ``compresslevel``, written atomically.

    Level 1 compresses 0/1 spike arrays about 4x faster than numpy's fixed level 6, for a file
    about 1.5x larger."""
    import zipfile

    import numpy as np

    with atomic_path(dest) as tmp:
        with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED, compresslevel=compresslevel) as zf:
            for name, value in arrays.items():
                with zf.open(f"{name}.npy", "w", force_zip64=True) as member:
                    np.lib.format.write_array(member, np.asanyarray(value), allow_pickle=False)
