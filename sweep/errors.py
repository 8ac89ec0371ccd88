"""Errors raised by ``sweep`` and the exit status the CLI maps each one to.

Every error derives from :class:`SweepError`; each subclass also inherits the builtin
that describes it, so ``except ValueError`` keeps working for callers that do not know
about ``sweep``.

Exit statuses of the ``sweep`` command (documented in ``sweep/README.md``):

==== ==========================================================================
0    success (a campaign whose points failed still succeeds: failures are data)
1    unexpected internal error (a bug: the traceback is printed)
2    bad input: campaign file, command-line arguments (:class:`ConfigError`)
3    store problem: locked, other campaign (file or journal), newer schema, not a sweep
     store, damaged with no journal, in use, disk full, invalid
     (:class:`StoreError` and subclasses)
4    MPI launch problem, e.g. size differs from ``SLURM_NTASKS`` (:class:`LaunchError`)
5    a worker process failed outside a point (:class:`WorkerError`)
6    interrupted by a signal (during start-up, the store's open or rebuild, the
     campaign or a merge); everything finished is stored and the campaign is
     resumable by running the same command again (:class:`Interrupted`)
==== ==========================================================================
"""
from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any

__all__ = ["SweepError", "ConfigError", "StoreError", "StoreLockedError",
           "SchemaVersionError", "CampaignMismatchError", "LaunchError", "WorkerError",
           "Interrupted", "PointNotFoundError", "StoreCorruptedError", "StoreUnreadableError",
           "UnstorableError", "BadJournalLineError", "NothingToDrawError", "EXIT_OK",
           "EXIT_INTERNAL", "EXIT_CONFIG", "EXIT_STORE", "EXIT_LAUNCH", "EXIT_WORKER",
           "EXIT_INTERRUPTED", "report", "command_status"]

EXIT_OK = 0
EXIT_INTERNAL = 1
EXIT_CONFIG = 2
EXIT_STORE = 3
EXIT_LAUNCH = 4
EXIT_WORKER = 5
EXIT_INTERRUPTED = 6


class SweepError(Exception):
    """Base class of every error raised by sweep; ``exit_status`` is the CLI's status."""

    exit_status = EXIT_INTERNAL


class ConfigError(SweepError, ValueError):
    """A campaign file or command-line argument is invalid (one message per bad value)."""

    exit_status = EXIT_CONFIG

    def __init__(self, messages: str | list[str]) -> None:
        self.messages = [messages] if isinstance(messages, str) else list(messages)
        super().__init__("\n".join(self.messages))


class StoreError(SweepError, OSError):
    """The result store cannot be used as asked."""

    exit_status = EXIT_STORE


class StoreLockedError(StoreError):
    """Another live campaign is writing the store."""


class SchemaVersionError(StoreError):
    """The store was written by a newer schema version than this sweep understands."""


class CampaignMismatchError(StoreError):
    """The store belongs to a different campaign (use ``--extend`` to add grid values)."""


class StoreCorruptedError(StoreError):
    """A stored row's ``config_json`` no longer hashes to its ``hash`` (the row was
    altered after it was written); ``hashes`` names the rows (as signac's
    ``JobsCorruptedError`` names its jobs)."""

    def __init__(self, message: str, hashes: list[str] | None = None) -> None:
        super().__init__(message)
        self.hashes = list(hashes or [])


class PointNotFoundError(SweepError, KeyError):
    """No stored point (or no profile) matches a hash or a parameter selection; a
    ``KeyError`` too, with a readable message (not the repr a plain ``KeyError`` shows)."""

    exit_status = EXIT_STORE

    def __init__(self, message: str, *, store: str = "", key: str = "") -> None:
        self.store = store
        self.key = key
        super().__init__(message)

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


class LaunchError(SweepError, RuntimeError):
    """The MPI launch is not what the environment expects (e.g. N singletons)."""

    exit_status = EXIT_LAUNCH


class WorkerError(SweepError, RuntimeError):
    """A worker failed outside a point (start-up, import); carries rank, host, traceback."""

    exit_status = EXIT_WORKER


class Interrupted(SweepError, RuntimeError):
    """The campaign stopped on a signal; what finished is stored and it is resumable."""

    exit_status = EXIT_INTERRUPTED


class StoreUnreadableError(StoreError):
    """A store file exists but HDF5 cannot open it (perhaps caught in the middle of a
    rebuild's rename: readers retry it)."""


class UnstorableError(SweepError, ValueError):
    """A record holds a value the schema cannot store; the message says which."""


class BadJournalLineError(SweepError, ValueError):
    """A journal line that cannot be trusted; the message is the reason."""


class NothingToDrawError(ConfigError):
    """No figure of the asked kinds can be drawn from the store's grid (exit status 2, as
    any input that cannot give what was asked); ``reasons`` maps each figure to why."""

    def __init__(self, message: str, reasons: dict[str, str]) -> None:
        super().__init__(message)
        self.reasons = dict(reasons)


def report(message: str | BaseException, prog: str = "sweep") -> None:
    """Report an error on stderr, one ``PROG: error:`` line per line of it; a requested stop
    (:class:`Interrupted`) is not an error and says ``PROG: stopped:`` instead."""
    prefix = f"{prog}: stopped:" if isinstance(message, Interrupted) else f"{prog}: error:"
    for line in str(message).splitlines() or [""]:
        print(f"{prefix} {line}", file=sys.stderr)


def command_status(command: Callable[[Any], int], args: Any, prog: str = "sweep") -> int:
    """``command(args)``'s exit status, with the errors a command may end by reported
    (:func:`report`) and mapped to their documented statuses: a :class:`SweepError` to its
    own, a missing key or file to :data:`EXIT_STORE`. Anything else propagates (the
    caller's: a bug, or a broken pipe)."""
    try:
        return command(args)
    except SweepError as exc:  # ConfigError, StoreError, ...: each carries its exit status
        report(exc, prog)
        return exc.exit_status
    except (KeyError, FileNotFoundError) as exc:
        report(str(exc), prog)
        return EXIT_STORE
