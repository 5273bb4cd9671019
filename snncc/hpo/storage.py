"""Where a study lives: an SQLite file by default, any Optuna RDB URL (PostgreSQL for many machines).

Heartbeats: every worker refreshes its running trial's heartbeat every ``heartbeat`` seconds; a
RUNNING trial whose heartbeat is older than ``grace`` seconds (its worker was killed) is marked
FAIL and its parameters are queued again (``optuna.storages.RetryHeartbeatStaleTrialCallback``),
so a finished trial is never run twice and a killed one is not lost.
"""

from __future__ import annotations

import contextlib
import os
import re
import time
import warnings
from pathlib import Path
from typing import Iterator

from snncc.errors import SnnccError

SQLITE_TIMEOUT_S = 60          # writers wait this long for SQLite's lock (several local workers)
CREATE_RETRIES = 6


def default_url(workdir: str | Path) -> str:
    return f"sqlite:///{Path(workdir).resolve() / 'hpo.sqlite3'}"


def study_storage_url(storage: str | None, workdir: str | Path, must_exist: bool = False) -> str:
    """``storage`` when given, else the SQLite file in ``workdir``; ``must_exist``: that file must be
    there already (reading a study: no storage, no study)."""
    if storage is not None:
        return storage
    if must_exist and not (Path(workdir) / "hpo.sqlite3").is_file():
        raise SnnccError("no study storage here (run snncc hpo run first, or give --storage)",
                         file=str(Path(workdir) / "hpo.sqlite3"), field="--dir")
    return default_url(workdir)


def report_command(study: str, storage: str | None, workdir: str | Path) -> str:
    """The ``snncc hpo report`` command line for ``study`` (the storage URL without its password)."""
    return f"snncc hpo report {study}" + (f" --storage '{redact(storage)}'" if storage else f" --dir {workdir}")


def redact(url: str) -> str:
    """``url`` without its password (for reports and logs)."""
    return re.sub(r"(://[^:/@]+:)[^@]*@", r"\1***@", url)


def sqlite_file(url: str) -> Path | None:
    """The database file of an SQLite URL (``sqlite:///rel.db``, ``sqlite:////abs.db``, or the URI
    form ``sqlite:///file:PATH?mode=ro&uri=true``); None for other schemes and in-memory databases."""
    if not url.startswith("sqlite:///"):
        return None
    path, _, query = url[len("sqlite:///"):].partition("?")
    if "uri=true" in query.lower().split("&") and path.startswith("file:"):
        path = path[len("file:"):]
    return Path(path) if path and path != ":memory:" else None


def shown(url: str) -> str:
    """How an error line names a storage: its SQLite file's path, else the URL without its scheme
    and password (a scheme's ``://`` would break the ``<file>: <field>: <rule>`` shape)."""
    db = sqlite_file(url)
    if db is not None:
        return str(db)
    return redact(url).split("://", 1)[-1] or url


def check_writable(url: str, field: str = "--storage") -> None:
    """Refuse, before any trial, an SQLite storage ``hpo run`` cannot write: a read-only file, a
    directory where SQLite cannot write its journal, or a URI opened read-only (``mode=ro``)."""
    db = sqlite_file(url)
    if db is None:
        return
    query = url.partition("?")[2].lower().split("&")
    if "mode=ro" in query or "immutable=1" in query:
        raise SnnccError("is opened read-only (mode=ro); hpo run records every trial in its storage",
                         file=str(db), field=field)
    if db.exists() and not os.access(db, os.W_OK):
        raise SnnccError("is read-only; hpo run records every trial in its storage (make it writable, or give "
                         "another --dir or --storage)", file=str(db), field=field)
    if db.parent.is_dir() and not os.access(db.parent, os.W_OK):
        raise SnnccError("its directory is read-only; SQLite writes a journal beside the database", file=str(db),
                         field=field)


@contextlib.contextmanager
def storage_errors(url: str, field: str = "--storage") -> Iterator[None]:
    """Turn the database's own failures (Optuna's StorageInternalError, SQLAlchemy's errors: a
    read-only or locked database, a lost server) into one line naming the storage."""
    import optuna

    try:
        yield
    except Exception as ex:
        if not (isinstance(ex, optuna.exceptions.StorageInternalError)
                or type(ex).__module__.startswith("sqlalchemy")):
            raise
        cause = ex.__cause__ or ex
        first = str(cause).strip().splitlines()[0] if str(cause).strip() else type(cause).__name__
        raise SnnccError(f"the study's database failed ({type(cause).__name__}: {first[:160]})", file=shown(url),
                         field=field) from None


def check_url(url: str, heartbeat: int = 30) -> str:
    """Refuse, without opening or creating anything, a storage ``open_storage`` could not open: a
    URL without a scheme, an SQLite file whose directory does not exist, a heartbeat below 1 s.
    Returns the URL's scheme."""
    if heartbeat < 1:
        raise SnnccError("must be >= 1 (seconds)", field="--heartbeat")
    scheme = url.split("://", 1)[0] if "://" in url else ""
    if not scheme or not re.fullmatch(r"[a-z0-9+]+", scheme):
        raise SnnccError("expected an Optuna storage URL such as sqlite:///path.db or "
                         "postgresql://user:pass@host/db", file=shown(url), field="--storage")
    path = sqlite_file(url) if scheme == "sqlite" else None
    if path is not None and not path.parent.is_dir():
        raise SnnccError("the SQLite file's directory does not exist", file=shown(url), field="--storage")
    return scheme


def open_storage(url: str, heartbeat: int = 30, grace: int | None = None):
    """An Optuna RDBStorage for ``url`` with heartbeats and the retry of stale trials (an SQLite
    file is created when missing: call it only once everything else was checked)."""
    import optuna
    from optuna.exceptions import ExperimentalWarning

    scheme = check_url(url, heartbeat)
    grace = grace if grace is not None else 2 * heartbeat + 1
    if scheme == "sqlite":
        kwargs: dict = {"connect_args": {"timeout": SQLITE_TIMEOUT_S}}
    else:
        kwargs = {"pool_pre_ping": True}
    for attempt in range(CREATE_RETRIES):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ExperimentalWarning)
                return optuna.storages.RDBStorage(
                    url, engine_kwargs=kwargs, heartbeat_interval=int(heartbeat), grace_period=int(grace),
                    heartbeat_stale_trial_callback=optuna.storages.RetryHeartbeatStaleTrialCallback())
        except ImportError as ex:
            missing = getattr(ex.__cause__, "name", None) or type(ex).__name__
            raise SnnccError(f"no database driver for {scheme!r} URLs (missing {missing}; PostgreSQL: "
                             "pip install 'snncc[postgres]')", file=shown(url), field="--storage") from None
        except Exception as ex:  # sqlalchemy: bad URL, unreachable server, bad credentials, a creation race
            if _creation_race(ex) and attempt + 1 < CREATE_RETRIES:
                time.sleep(0.5 * (attempt + 1))   # another worker is creating the tables this instant
                continue
            first = str(ex).strip().splitlines()[0] if str(ex).strip() else type(ex).__name__
            raise SnnccError(f"cannot open the storage ({type(ex).__name__}: {first[:160]})", file=shown(url),
                             field="--storage") from None
    raise AssertionError("unreachable")


def _creation_race(ex: Exception) -> bool:
    """Two workers creating a fresh storage's tables at once: one of them sees a duplicate."""
    text = str(ex).lower()
    return type(ex).__name__ == "IntegrityError" or "already exists" in text or "database is locked" in text
