"""``python -m sweep ARGS`` as a process of its own, forked from an interpreter that imported
sweep once, for the tests whose subject is the command's life, not the interpreter's start-up.

A fresh ``python -m sweep run`` spends about 0.6 s importing numpy, numba, scipy, h5py and
sweep before it reads its arguments; a test that runs the command a few times to see its
exit statuses, messages, signals and store spends most of its time there. :func:`run` and
:func:`popen` (the shapes of :func:`subprocess.run` and :class:`subprocess.Popen`) hand the
command to a server that did those imports once (one per pytest process; a command whose
import-time environment, :data:`IMPORT_TIME`, differs runs fresh) and forks a child for each
command. The child takes the command's standard streams, working directory, environment and
``sys.argv``, runs ``sweep/__main__.py`` as ``python -m sweep`` does (the guard of
``sweep run`` included), and exits as the interpreter does (the status of its ``SystemExit``, a
traceback and 1 for an exception, SIGINT for KeyboardInterrupt; non-daemon threads joined,
``atexit`` handlers, a ``-c`` script's globals released, HDF5 files still open closed, the
streams flushed: 120 if that fails), except that the modules are not torn down one by one
(0.2 s a child) and C-level exit handlers other than HDF5's close are skipped. Its pid is
the command's: signals are sent to it, and its status is ``os.waitstatus_to_exitcode``'s,
negative for a signal. ``module=`` runs another module (``python -m floewave``), ``code=`` a
``python -c`` script. tests/test_forkserver.py checks it against a fresh interpreter.

Not the same as a fresh interpreter, and so not used by the tests of these: a stop signal
during the interpreter's start-up or an import (tests/sweep/test_store_holes.py, and
test_store_safety.py's start-up stop and merge stop, keep fresh interpreters for those),
what a command imports (tests/sweep/test_api.py), and the console script itself
(tests/sweep/test_cli.py). The slow tier runs fresh interpreters throughout (the MPI
torture, Slurm, the docs' launcher walks).
"""
from __future__ import annotations

import atexit
import contextlib
import json
import os
import selectors
import socket
import subprocess
import sys
import time
from collections.abc import Mapping
from pathlib import Path

#: Environment variables read when a module is imported (numba's, Python's, and sweep's
#: ``SWEEP_CHILD_MARGIN`` and ``SWEEP_HARD_TIMEOUT_MIN`` in sweep/run/compute.py): a command
#: whose values differ from the server's runs in a fresh interpreter.
#: (``PYTHONPATH``'s entries are put on the child's ``sys.path``.)
IMPORT_TIME = ("NUMBA_", "PYTHON", "SWEEP_CHILD_MARGIN", "SWEEP_HARD_TIMEOUT_MIN")

_SERVER = r"""
import atexit, contextlib, gc, json, os, runpy, select, signal, socket, sys, threading
import traceback
# what `python -m sweep` imports for run, status, validate and merge, once
import scipy.optimize, h5py, numba, numpy
import sweep, sweep.cli, sweep.run.launch, sweep.run.compute, sweep.testing, sweep.store.store
import sweep.analysis.status

sock = socket.socket(fileno=int(sys.argv[1]))
started_with = set(sys.path)


def child(request, fds):
    code = 1
    try:
        code = command(request, fds)
    except BaseException:  # the set-up or the exit sequence itself failed
        with contextlib.suppress(BaseException):
            traceback.print_exc()
    finally:
        os._exit(code & 0xFF)


def command(request, fds):
    sock.close()
    for target, fd in enumerate(fds):
        os.dup2(fd, target)
    for fd in set(fds):
        if fd > 2:
            os.close(fd)
    if request["new_session"]:
        os.setsid()
    os.chdir(request["cwd"])
    os.environ.clear()
    os.environ.update(request["env"])
    # python -m puts the working directory first, python -c "", then PYTHONPATH's entries
    sys.path[0] = "" if request["code"] is not None else os.getcwd()
    sys.path[1:1] = [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep)
                     if p and p not in started_with]
    namespace = {"__name__": "__main__"}
    code, interrupted = 0, False
    try:
        if request["code"] is None:
            sys.argv = [None, *request["args"]]  # runpy sets [0]: the module's __main__.py
            runpy.run_module(request["module"], run_name="__main__", alter_sys=True)
        else:
            sys.argv = ["-c", *request["args"]]
            exec(compile(request["code"], "<string>", "exec"), namespace)  # noqa: S102
    except SystemExit as exc:  # as the interpreter reads it
        if exc.code is None or isinstance(exc.code, int):
            code = exc.code or 0
        else:
            print(exc.code, file=sys.stderr)
            code = 1
    except BaseException as exc:  # the traceback (from the command's frame), then 1
        sys.excepthook(type(exc), exc, exc.__traceback__.tb_next)
        code, interrupted = 1, isinstance(exc, KeyboardInterrupt)  # SIGINT, below
    # the interpreter's exit, short of tearing down every module (0.2 s in a child that
    # shares the server's pages): non-daemon threads joined, atexit handlers, the script's
    # globals released (finalisers), HDF5 files still open closed (as HDF5's own exit
    # handler does), the streams flushed (120 if that fails)
    try:
        threading._shutdown()
    except BaseException:  # a stop while waiting for the threads: reported, not fatal
        print("Exception ignored on threading shutdown:", file=sys.stderr)
        traceback.print_exc()
    atexit._run_exitfuncs()
    del namespace
    gc.collect()
    for fid in h5py.h5f.get_obj_ids(types=h5py.h5f.OBJ_FILE):
        with contextlib.suppress(Exception):
            h5py.File(fid).close()
    for stream in (sys.stdout, sys.stderr):
        if stream is not None and not stream.closed:
            try:
                stream.flush()
            except Exception as exc:  # noqa: BLE001
                with contextlib.suppress(Exception):
                    print(f"Exception ignored in: {stream!r}\n{type(exc).__name__}: {exc}",
                          file=sys.__stderr__)
                code = 120
    if interrupted:
        signal.signal(signal.SIGINT, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGINT)
    return code


gc.freeze()  # the children's collections leave the server's objects (and pages) alone
sock.send(json.dumps({"ready": os.getpid()}).encode())
children = {}  # pid -> the request's number: a pid is unique only until it is reaped
while True:
    ready, _, _ = select.select([sock], [], [], 0.005 if children else None)
    if ready:
        message, fds, _, _ = socket.recv_fds(sock, 1 << 20, 3)
        if not message:
            break
        request = json.loads(message)
        pid = os.fork()
        if pid == 0:
            child(request, fds)
        for fd in fds:
            os.close(fd)
        children[pid] = request["n"]
        sock.send(json.dumps({"started": pid, "n": request["n"]}).encode())
    while children:
        pid, status = os.waitpid(-1, os.WNOHANG)
        if pid == 0:
            break
        n = children.pop(pid, None)  # (a child of no request: none is forked so)
        if n is not None:
            sock.send(json.dumps({"ended": n, "status": status}).encode())
"""


class _Server:
    """One forking interpreter and the socket to it."""

    def __init__(self, env: dict[str, str]):
        self.sock, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        self.proc = subprocess.Popen(
            [sys.executable, "-c", _SERVER, str(theirs.fileno())], pass_fds=[theirs.fileno()],
            env=env, cwd=Path(__file__).resolve().parent.parent,
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL)
        theirs.close()
        # wait statuses by request number, not by pid: the kernel hands an ended command's
        # pid to a later process (pid_max is 32768 here, and a full test run starts more
        # processes than that), and a status kept by pid would be read as the new one's
        self.status: dict[int, int] = {}
        self.requests = 0
        self.ready = False
        self.env = env

    def start(self, request: dict, fds: list[int]) -> tuple[int, int]:
        """The command's pid and its request number (the key of its status)."""
        self.requests += 1
        n = self.requests
        socket.send_fds(self.sock, [json.dumps({**request, "n": n}).encode()], fds)
        while True:
            message = self._receive(None)
            if message.get("n") == n and "started" in message:
                return message["started"], n

    def _receive(self, timeout: float | None) -> dict | None:
        self.sock.settimeout(timeout)  # 0: only what has arrived
        try:
            data = self.sock.recv(1 << 16)
        except (TimeoutError, BlockingIOError):
            return None
        if not data:
            raise RuntimeError(f"the fork server ended (status {self.proc.poll()})")
        message = json.loads(data)
        self.ready = True
        if "ended" in message:
            self.status[message["ended"]] = message["status"]
        return message

    def wait(self, n: int, timeout: float | None) -> int | None:
        """The wait status of request ``n``'s command, or ``None`` if it has not ended after
        ``timeout`` seconds (0: the messages the server has sent so far are read, none
        awaited)."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while n not in self.status:
            left = None if deadline is None else max(0.0, deadline - time.monotonic())
            if self._receive(left) is None:
                break
        return self.status.get(n)

    def close(self) -> None:
        self.sock.close()
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()


_server_of_this_process: list[_Server] = []


def _import_time(env: Mapping[str, str]) -> tuple:
    return tuple(sorted((k, v) for k, v in env.items()
                        if k.startswith(IMPORT_TIME) and k != "PYTHONPATH"))


def _server(env: Mapping[str, str]) -> _Server | None:
    """This process's server (started with its environment on first use), or ``None`` for
    an ``env`` whose import-time variables differ: such a command needs a fresh
    interpreter."""
    if not _server_of_this_process:
        _server_of_this_process.append(_Server(dict(os.environ)))
        atexit.register(_server_of_this_process[0].close)
    server = _server_of_this_process[0]
    return server if _import_time(env) == _import_time(server.env) else None


def _command(args, module: str, code: str | None) -> list[str]:
    """The fresh interpreter's command line."""
    return [sys.executable, *(["-c", code] if code is not None else ["-m", module]),
            *map(str, args)]


def prestart(wait: bool = False) -> None:
    """Start this process's server now, so that its imports overlap other work; with
    ``wait``, return once it has imported them (so that a test can time a command without
    them)."""
    server = _server(os.environ)
    while wait and not server.ready:
        server._receive(None)


class Forked:
    """A running ``python -m sweep`` command: the parts of :class:`subprocess.Popen` the
    tests use (``pid``, ``stdout``, ``stderr``, ``returncode``, ``poll``, ``wait``,
    ``communicate``, ``send_signal``, ``terminate``, ``kill``)."""

    def __init__(self, args, *, module="sweep", code=None, env=None, cwd=None, stdin=None,
                 stdout=None, stderr=None, text=False, start_new_session=False):
        env = dict(os.environ if env is None else env)
        self.args = ["python", *(["-c", "CODE"] if code is not None else ["-m", module]),
                     *map(str, args)]
        server = _server(env)
        if server is None:
            raise ValueError("a fresh interpreter's command (its import-time environment"
                             " differs from the server's): use popen() or run()")
        self._server = server
        self.returncode: int | None = None
        ours, theirs, close = {}, [], []
        for fd, how in enumerate((stdin, stdout, stderr)):
            if how is None:
                theirs.append(fd)
            elif how == subprocess.DEVNULL:
                null = os.open(os.devnull, os.O_RDWR)
                theirs.append(null)
                close.append(null)
            elif how == subprocess.PIPE:
                r, w = os.pipe()
                parent, child = (w, r) if fd == 0 else (r, w)
                ours[fd] = parent
                theirs.append(child)
                close.append(child)
            elif how == subprocess.STDOUT and fd == 2:
                theirs.append(theirs[1])
            else:
                theirs.append(how if isinstance(how, int) else how.fileno())
        try:
            self.pid, self._n = self._server.start(
                {"args": [str(a) for a in args], "module": module, "code": code, "env": env,
                 "cwd": str(Path.cwd() if cwd is None else cwd),
                 "new_session": bool(start_new_session)}, theirs)
        finally:
            for fd in close:
                os.close(fd)
        self._text = text
        self._read: dict = {}  # what communicate() has read, by stream

        def stream(fd):
            if fd not in ours:
                return None
            return open(ours[fd], ("w" if fd == 0 else "r") + ("" if text else "b"))

        self.stdin, self.stdout, self.stderr = stream(0), stream(1), stream(2)

    def _set(self, status: int | None) -> int | None:
        if status is not None:
            self.returncode = os.waitstatus_to_exitcode(status)
        return self.returncode

    def poll(self) -> int | None:
        if self.returncode is None:
            self._set(self._server.wait(self._n, 0))
        return self.returncode

    def wait(self, timeout: float | None = None) -> int:
        if self.returncode is None and self._set(self._server.wait(self._n, timeout)) is None:
            raise subprocess.TimeoutExpired(self.args, timeout)
        return self.returncode

    def communicate(self, input=None, timeout: float | None = None):
        """As :meth:`subprocess.Popen.communicate`: ``input`` to stdin, then stdout and
        stderr read to their ends; after a :class:`subprocess.TimeoutExpired` (whose
        ``stdout``/``stderr`` hold what was read) a call again goes on where it stopped."""
        deadline = None if timeout is None else time.monotonic() + timeout
        if self.stdin is not None and not self.stdin.closed:
            with contextlib.suppress(BrokenPipeError):  # it ended without reading: as Popen
                if input:
                    self.stdin.write(input)
                self.stdin.close()
        out = self._read
        sel = selectors.DefaultSelector()
        for f in (self.stdout, self.stderr):
            if f is not None and not f.closed:
                out.setdefault(f, [])
                sel.register(f.fileno(), selectors.EVENT_READ, f)
        while sel.get_map():
            left = None if deadline is None else deadline - time.monotonic()
            if left is not None and left <= 0:
                raise subprocess.TimeoutExpired(self.args, timeout, *self._joined(out, False))
            for key, _ in sel.select(left):
                data = os.read(key.fd, 1 << 16)
                if not data:
                    sel.unregister(key.fd)
                    key.data.close()
                else:
                    out[key.data].append(data)
        self.wait(None if deadline is None else max(0.0, deadline - time.monotonic()))
        return self._joined(out, True)

    def _joined(self, out: dict, text: bool) -> tuple:
        def one(f):
            if f is None:
                return None
            data = b"".join(out.get(f, []))
            return data.decode() if text and self._text else data

        return one(self.stdout), one(self.stderr)

    def close(self) -> None:
        """Close this side of its pipes."""
        for f in (self.stdin, self.stdout, self.stderr):
            if f is not None and not f.closed:
                f.close()

    def send_signal(self, sig: int) -> None:
        if self.poll() is None:
            try:
                os.kill(self.pid, sig)
            except ProcessLookupError:  # ended (and reaped by the server) since the poll,
                pass                    # as subprocess.Popen.send_signal allows

    def terminate(self) -> None:
        self.send_signal(15)

    def kill(self) -> None:
        self.send_signal(9)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        self.wait()


def popen(args, *, module="sweep", code=None, **kw) -> Forked | subprocess.Popen:
    """``subprocess.Popen([python, -m, sweep, *args], **kw)``, forked; with ``module=NAME``,
    ``python -m NAME *args``; with ``code=TEXT``, ``python -c TEXT *args`` (``env``, ``cwd``,
    ``stdin``/``stdout``/``stderr`` as None, ``DEVNULL``, ``PIPE``, a file or fd,
    ``text`` and ``start_new_session``). An ``env`` whose import-time variables
    (:data:`IMPORT_TIME`) differ from this process's runs it in a fresh interpreter."""
    if _server(os.environ if kw.get("env") is None else kw["env"]) is None:
        return subprocess.Popen(_command(args, module, code), **kw)
    return Forked(args, module=module, code=code, **kw)


def run(args, *, module="sweep", code=None, env=None, cwd=None, timeout=None, capture_output=False,
        text=False, input=None, stdout=None, stderr=None) -> subprocess.CompletedProcess:
    """``subprocess.run([python, -m, sweep, *args], ...)`` (or ``python -c code``), forked
    (or fresh, as :func:`popen`), with subprocess's defaults; on ``timeout`` the command is
    killed and :class:`subprocess.TimeoutExpired` raised, as subprocess does."""
    if capture_output:
        stdout = stderr = subprocess.PIPE
    if _server(os.environ if env is None else env) is None:
        return subprocess.run(_command(args, module, code), env=env, cwd=cwd, timeout=timeout,
                              text=text, input=input, stdout=stdout, stderr=stderr)
    p = Forked(args, module=module, code=code, env=env, cwd=cwd,
               stdin=subprocess.PIPE if input is not None else None, stdout=stdout,
               stderr=stderr, text=text)
    try:
        out, err = p.communicate(input, timeout)
    except subprocess.TimeoutExpired:
        p.kill()
        p.wait()
        p.close()
        raise
    return subprocess.CompletedProcess(p.args, p.returncode, out, err)
