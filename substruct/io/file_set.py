"""Files written as one set: a lock on the output directory, a staging folder beside the
targets, and a commit that moves the whole set into place or nothing of it.

A command that writes several files that belong together (a result and its pictures, a VTU
export and its companions) follows four steps:

1. :class:`OutputDir` takes an exclusive lock on the directory (``fcntl.flock`` on the
   directory itself, so that a killed writer leaves no lock file; on a file system that
   cannot lock directories, on a lock file ``.substruct.lock`` in it, removed again): a second
   writer fails at once with :class:`BusyError`.  Holding
   the lock, it removes what killed runs left behind (staging folders and temporary files,
   every name starting with ``.substruct-``) and finishes a commit that was under way.
2. :meth:`OutputDir.stage` makes a staging folder ``.substruct-<name>.<random>.part`` in the
   directory; the files are written there under their final names.
3. :meth:`OutputDir.commit` writes a journal (the names of the previous set that go) into the
   folder, renames it to ``... .commit`` (the point of no return), then moves every file into
   place and removes the old names; SIGINT and SIGTERM wait while it does so (a few renames).
   A run killed in the middle (SIGKILL) leaves the ``.commit`` folder, which the next writer
   completes before anything else: readers see the previous set or the new one.
4. Leaving the ``with`` block releases the lock; on an error the staging folder is removed,
   and so are the directories the block created if they stayed empty.

A failure of the file system while the set is staged or committed (a full disk, a folder made
read-only or removed meanwhile) is a :class:`~substruct.io.paths.WriteError` (one line); the
staged files go with the staging folder, so nothing of the new set is left.  Only a failure in
the middle of step 3 (past the point of no return) leaves the ``.commit`` folder, which the
next writer completes.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import tempfile
import threading
from pathlib import Path
from types import TracebackType
from typing import Iterable, Iterator

from substruct.io.paths import TEMP_PREFIX, WriteError, plain_name, resolved_dir, write_errors

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX: no locking
    fcntl = None  # type: ignore[assignment]

__all__ = ["BusyError", "WriteError", "OutputDir", "LOCK_NAME", "TEMP_PREFIX",
           "signals_held", "remove_stale"]

#: The lock file in an output directory that cannot be locked itself (removed when done).
LOCK_NAME = ".substruct.lock"
_JOURNAL = ".substruct-journal"


class BusyError(Exception):
    """Another process holds the lock of the output directory."""


@contextlib.contextmanager
def signals_held() -> Iterator[None]:
    """Hold SIGINT and SIGTERM back while the block runs (they act right after it)."""
    held = {signal.SIGINT, signal.SIGTERM}
    if threading.current_thread() is not threading.main_thread() or \
            not hasattr(signal, "pthread_sigmask"):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, held)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def _roll_forward(folder: Path, out: Path) -> list[Path]:
    """Finish the commit recorded in ``folder``: remove the journal's names, move its files."""
    journal = folder / _JOURNAL
    gone = journal.read_text(encoding="utf-8").splitlines() if journal.exists() else []
    moved = []
    files = sorted((p for p in folder.iterdir() if p.name != _JOURNAL),
                   key=lambda p: (p.suffix == ".h5", p.name))  # the result file last
    new = {p.name for p in files}
    for name in gone:
        if plain_name(name) and name not in new:
            with contextlib.suppress(FileNotFoundError, IsADirectoryError):
                (out / name).unlink()
    for p in files:
        os.replace(p, out / p.name)
        moved.append(out / p.name)
    journal.unlink(missing_ok=True)
    folder.rmdir()
    return moved


def remove_stale(out: Path) -> list[str]:
    """Complete interrupted commits and remove staging folders and temporary files of killed
    runs in ``out`` (names starting with :data:`TEMP_PREFIX`); return the names handled.

    Only call it holding the directory's lock (:class:`OutputDir`)."""
    handled = []
    for p in sorted(out.iterdir()):
        if not p.name.startswith(TEMP_PREFIX) or p.is_symlink():
            continue
        if p.name.endswith(".commit") and p.is_dir():
            _roll_forward(p, out)
        elif p.is_dir():
            shutil.rmtree(p, ignore_errors=True)
        else:
            p.unlink(missing_ok=True)
        handled.append(p.name)
    return handled


class OutputDir:
    """An output directory held for writing (a context manager).

    Args:
        path: the directory; missing directories are created on entry (and removed again on
            an error if they stayed empty).

    Raises:
        BusyError: on entry, when another process writes into the directory.
    """

    def __init__(self, path: str | os.PathLike):
        self.path = resolved_dir(path)
        self.created: list[Path] = []
        self.stale: list[str] = []
        self._fd: int | None = None
        self._lock_path: Path | None = None
        self._staging: list[Path] = []

    def __enter__(self) -> OutputDir:
        missing = []
        probe = self.path
        while not probe.exists() and probe.parent != probe:
            missing.append(probe)
            probe = probe.parent
        try:
            with write_errors(self.path):
                for d in reversed(missing):
                    d.mkdir()
                    self.created.append(d)
        except BaseException:
            self._remove_created()
            raise
        try:
            with write_errors(self.path):
                self._lock()
                self.stale = remove_stale(self.path)
        except BaseException:
            self._remove_created()
            raise
        return self

    def __exit__(self, kind: type[BaseException] | None, err: BaseException | None,
                 tb: TracebackType | None) -> None:
        try:
            for folder in self._staging:
                shutil.rmtree(folder, ignore_errors=True)
        finally:
            self._unlock()
            if kind is not None:
                self._remove_created()

    def _lock(self) -> None:
        if fcntl is None:  # pragma: no cover
            return
        fd = os.open(self.path, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0)
                     | getattr(os, "O_CLOEXEC", 0))
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            raise BusyError(f"another run is writing {self.path}") from None
        except OSError:  # a file system without locks on directories: a lock file
            os.close(fd)
            self._lock_file()
            return
        self._fd = fd

    def _lock_file(self) -> None:
        lock = self.path / LOCK_NAME
        while True:
            fd = os.open(lock, os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0)
                         | getattr(os, "O_CLOEXEC", 0), 0o666)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                os.close(fd)
                raise BusyError(f"another run is writing {self.path}") from None
            mine = os.fstat(fd)
            try:
                now = os.stat(lock, follow_symlinks=False)
            except FileNotFoundError:
                now = None
            if now is not None and (now.st_dev, now.st_ino) == (mine.st_dev, mine.st_ino):
                self._fd, self._lock_path = fd, lock
                return
            os.close(fd)  # the holder removed the file as we opened it: take the new one

    def _unlock(self) -> None:
        if self._fd is not None:
            if self._lock_path is not None:
                self._lock_path.unlink(missing_ok=True)
            os.close(self._fd)
            self._fd, self._lock_path = None, None

    def _remove_created(self) -> None:
        for d in reversed(self.created):
            with contextlib.suppress(OSError):
                d.rmdir()

    def stage(self, name: str) -> Path:
        """A new, empty staging folder for the set called ``name`` (removed on exit unless
        committed)."""
        with write_errors(self.path):
            folder = Path(tempfile.mkdtemp(dir=self.path, prefix=f"{TEMP_PREFIX}{name}.",
                                           suffix=".part"))
        self._staging.append(folder)
        return folder

    def commit(self, folder: Path, remove: Iterable[str] = ()) -> list[Path]:
        """Move every file of the staging ``folder`` into the directory and remove the names
        ``remove`` (files of the previous set that the new set does not have), as one step;
        return the paths now in place.

        Raises:
            WriteError: the file system refused a step (nothing moved if it refused before
                the point of no return; else the next writer completes the commit).
        """
        gone = sorted({n for n in remove if plain_name(n)})
        done = folder.with_name(folder.name.removesuffix(".part") + ".commit")
        with write_errors(self.path):
            (folder / _JOURNAL).write_text("".join(f"{n}\n" for n in gone), encoding="utf-8")
            with signals_held():
                os.rename(folder, done)
                self._staging.remove(folder)
                return _roll_forward(done, self.path)
