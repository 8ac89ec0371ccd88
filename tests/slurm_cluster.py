"""A real single-node Slurm for the tests of ``slurm/*.sbatch`` (tests/test_slurm.py).

:class:`SlurmCluster` starts ``munged``, ``slurmctld`` and ``slurmd`` (Debian's ``munge``
and ``slurm-wlm``) as root, in the foreground, from a configuration in a new directory
under /tmp: its own munge key and socket, free TCP ports on 127.0.0.1, one node whose CPU
count is overridden (``SlurmdParameters=config_overrides``) so that a few ranks fit on a
2-core machine, ``proctrack/linuxproc``, ``select/cons_tres``, ``task/none``, one default
partition, no accounting database (``scontrol show job`` keeps finished jobs for an hour;
``jobcomp/filetxt`` records every end of every job, requeues included). Nothing outside
that directory is touched, so it can run beside another Slurm or another test session.
:meth:`SlurmCluster.stop` cancels what is left and stops the daemons.
"""
from __future__ import annotations

import ctypes
import os
import random
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: The programs the tests need (packages slurm-wlm and munge).
PROGRAMS = ("munged", "slurmctld", "slurmd", "sbatch", "scontrol", "scancel", "squeue",
            "sinfo")
NODE = "fwnode"
#: CPUs the node claims (the machine may have fewer): 3 MPI ranks + one array task fit.
CPUS = 4
#: Job states after which nothing more happens to a job (unless it is requeued).
FINAL = {"COMPLETED", "CANCELLED", "FAILED", "TIMEOUT", "NODE_FAIL", "OUT_OF_MEMORY",
         "BOOT_FAIL", "DEADLINE", "PREEMPTED"}


def missing_programs() -> list[str]:
    return [p for p in PROGRAMS if shutil.which(p) is None]


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _die_with_parent() -> None:
    """In a daemon's child process: SIGTERM when the test process dies (a killed pytest
    leaves no daemons behind)."""
    pr_set_pdeathsig = 1
    ctypes.CDLL(None, use_errno=True).prctl(pr_set_pdeathsig, signal.SIGTERM)


def _tail(path: Path, n: int = 20) -> str:
    try:
        return "\n".join(path.read_text(errors="replace").splitlines()[-n:])
    except OSError:
        return "(none)"


def _fnv1a(text: str) -> int:
    h = 2166136261
    for b in text.encode():
        h = ((h ^ b) * 16777619) & 0xFFFFFFFF
    return h


def remove_mpich_leftovers(jobs: list[str], steps: int = 10) -> list[str]:
    """Remove the node-local shared memory that MPICH ranks killed with SIGKILL left in
    /dev/shm: ``mpich_shm_<FNV-1a of the PMI job id, JOBID.STEP under srun>_<node>`` (and
    ``mpich_vci_…``), for the steps 0..steps-1 of ``jobs``, nothing else."""
    removed = []
    shm = Path("/dev/shm")
    for job in jobs:
        for step in range(steps):
            h = f"{_fnv1a(f'{job}.{step}'):x}"
            for path in [*shm.glob(f"mpich_shm_{h}_*"), *shm.glob(f"mpich_vci_{h}_*")]:
                try:
                    path.unlink()
                    removed.append(path.name)
                except OSError:
                    pass
    return removed


class SlurmError(RuntimeError):
    """A Slurm command failed, or a job did not reach a state in time."""


class SlurmCluster:
    """A single-node Slurm of this test session (see the module docstring)."""

    def __init__(self) -> None:
        # munged wants every directory above its socket searchable by all, and the socket
        # path must stay short: a directory of its own under /tmp, mode 0755
        self.dir = Path(tempfile.mkdtemp(prefix="fw-slurm-", dir="/tmp"))
        self.dir.chmod(0o755)
        self.conf = self.dir / "slurm.conf"
        self.logs = self.dir / "log"
        self.procs: dict[str, subprocess.Popen] = {}
        self.submitted: list[str] = []

    # ----------------------------------------------------------------- daemons
    def start(self, timeout: float = 60.0) -> None:
        d = self.dir
        for sub in ("munge", "state", "spool", "log"):
            (d / sub).mkdir()
            (d / sub).chmod(0o755)
        key = d / "munge" / "munge.key"
        key.write_bytes(os.urandom(1024))
        key.chmod(0o600)
        self.munge_socket = d / "munge" / "sock"
        self._spawn("munged", ["munged", "--foreground", f"--key-file={key}",
                               f"--socket={self.munge_socket}",
                               f"--pid-file={d / 'munge' / 'munged.pid'}",
                               f"--log-file={self.logs / 'munged.log'}",
                               f"--seed-file={d / 'munge' / 'seed'}"])
        self._wait(lambda: self.munge_socket.exists(), 10.0, "munged did not create its socket")
        self.conf.write_text(self._config())
        self._spawn("slurmctld", ["slurmctld", "-D", "-c", "-f", str(self.conf)])
        self._spawn("slurmd", ["slurmd", "-D", "-N", NODE, "-f", str(self.conf)])

        def idle() -> bool:
            r = self.run("sinfo", "-h", "-n", NODE, "-o", "%T", check=False)
            return r.returncode == 0 and r.stdout.strip() == "idle"
        self._wait(idle, timeout, "the node did not become idle")

    def _config(self) -> str:
        d = self.dir
        return "\n".join([
            "ClusterName=floewavetest",
            "SlurmctldHost=localhost(127.0.0.1)",
            f"SlurmctldPort={_free_port()}",
            f"SlurmdPort={_free_port()}",
            "SlurmUser=root",
            "SlurmdUser=root",
            "AuthType=auth/munge",
            "CredType=cred/munge",
            f"AuthInfo=socket={self.munge_socket}",
            f"StateSaveLocation={d / 'state'}",
            f"SlurmdSpoolDir={d / 'spool'}",
            f"SlurmctldPidFile={d / 'slurmctld.pid'}",
            f"SlurmdPidFile={d / 'slurmd.pid'}",
            f"SlurmctldLogFile={self.logs / 'slurmctld.log'}",
            f"SlurmdLogFile={self.logs / 'slurmd.log'}",
            "ProctrackType=proctrack/linuxproc",
            "TaskPlugin=task/none",
            "SelectType=select/cons_tres",
            "SelectTypeParameters=CR_Core",
            "SlurmdParameters=config_overrides",
            "MpiDefault=none",
            "ReturnToService=2",
            "MinJobAge=3600",
            # job ids of their own: MPICH names its shared memory after JOBID.STEP, and a
            # step killed by a test leaves that file in /dev/shm (see remove_mpich_leftovers)
            f"FirstJobId={random.randrange(1_000_000, 60_000_000)}",
            # schedule at once (a released requeued job would wait for the next pass)
            "SchedulerType=sched/builtin",
            "SchedulerParameters=sched_interval=1",
            "KillWait=10",
            "JobAcctGatherType=jobacct_gather/none",
            "AccountingStorageType=accounting_storage/none",
            "JobCompType=jobcomp/filetxt",
            f"JobCompLoc={self.logs / 'jobcomp.txt'}",
            f"NodeName={NODE} NodeHostname={socket.gethostname()} NodeAddr=127.0.0.1"
            f" CPUs={CPUS} State=UNKNOWN",
            f"PartitionName=debug Nodes={NODE} Default=YES MaxTime=INFINITE State=UP",
            ""])

    def _spawn(self, name: str, cmd: list[str]) -> None:
        out = open(self.logs / f"{name}.out", "w")  # noqa: SIM115 - kept open with the daemon
        self.procs[name] = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT,
                                            stdin=subprocess.DEVNULL, start_new_session=True,
                                            preexec_fn=_die_with_parent)

    def _wait(self, ok, timeout: float, what: str) -> None:
        deadline = time.monotonic() + timeout
        while not ok():
            for name, p in self.procs.items():
                if p.poll() is not None:
                    raise SlurmError(f"{name} exited with {p.returncode}\n{self.diagnostics()}")
            if time.monotonic() > deadline:
                raise SlurmError(f"{what} within {timeout:g} s\n{self.diagnostics()}")
            time.sleep(0.1)

    def diagnostics(self) -> str:
        parts = []
        for f in sorted(self.logs.glob("*")):
            parts.append(f"--- {f.name}:\n{_tail(f)}")
        return "\n".join(parts)

    def stop(self) -> None:
        """Cancel every job, wait for them to end, stop the daemons."""
        if "slurmctld" in self.procs and self.procs["slurmctld"].poll() is None:
            self.run("scancel", "--full", "--user=root", check=False)
            deadline = time.monotonic() + 30
            while time.monotonic() < deadline:
                r = self.run("squeue", "-h", "-o", "%i", check=False)
                if r.returncode != 0 or not r.stdout.strip():
                    break
                time.sleep(0.5)
        remove_mpich_leftovers(self.submitted)
        for name in ("slurmd", "slurmctld", "munged"):
            p = self.procs.get(name)
            if p is None or p.poll() is not None:
                continue
            p.send_signal(signal.SIGTERM)
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()

    # ----------------------------------------------------------------- clients
    def env(self, **changes: str | None) -> dict[str, str]:
        """The environment of client commands and jobs: this session's, the Python's bin
        directory first on PATH (``sweep``, ``mpiexec``), SLURM_CONF, no variables of an
        enclosing Slurm job; ``changes`` set (or with None, remove) variables."""
        env = {k: v for k, v in os.environ.items() if not k.startswith(("SLURM_", "SBATCH_"))}
        env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
        env["SLURM_CONF"] = str(self.conf)
        for k, v in changes.items():
            if v is None:
                env.pop(k, None)
            else:
                env[k] = v
        return env

    def run(self, *cmd: str, check: bool = True, env: dict[str, str] | None = None
            ) -> subprocess.CompletedProcess:
        r = subprocess.run(cmd, capture_output=True, text=True, env=env or self.env(),
                           timeout=60)
        if check and r.returncode != 0:
            raise SlurmError(f"{' '.join(cmd)}: exit {r.returncode}: {r.stderr.strip()}")
        return r

    def sbatch(self, *args: str, env: dict[str, str] | None = None) -> str:
        """Submit; returns the job id."""
        job = self.run("sbatch", "--parsable", *args, env=env).stdout.strip().split(";")[0]
        self.submitted.append(job)
        return job

    def jobs(self, job: str) -> list[dict[str, str]]:
        """``scontrol show job`` of ``job`` (one record per array task)."""
        out = self.run("scontrol", "show", "job", "-o", job).stdout
        return [dict(kv.split("=", 1) for kv in line.split() if "=" in kv)
                for line in out.splitlines() if line.strip()]

    def job(self, job: str) -> dict[str, str]:
        return self.jobs(job)[0]

    def steps(self, job: str) -> list[str]:
        r = self.run("squeue", "-h", "-s", "-j", job, "-o", "%i", check=False)
        return r.stdout.split()

    def wait(self, job: str, states: set[str] | str = frozenset(FINAL), timeout: float = 90.0,
             restarts: int | None = None) -> dict[str, str]:
        """Wait until every record of ``job`` is in one of ``states`` (and, if given, has
        ``restarts`` restarts); returns the (first) record."""
        states = {states} if isinstance(states, str) else set(states)
        deadline = time.monotonic() + timeout
        while True:
            recs = self.jobs(job)
            if recs and all(r["JobState"] in states and
                            (restarts is None or int(r["Restarts"]) == restarts)
                            for r in recs):
                return recs[0]
            if time.monotonic() > deadline:
                brief = [{k: r.get(k) for k in ("JobId", "JobState", "Reason", "Restarts",
                                                 "ExitCode")} for r in recs]
                raise SlurmError(f"job {job} not {sorted(states)} (restarts {restarts})"
                                 f" within {timeout:g} s: {brief}")
            time.sleep(0.1)

    def release(self, job: str) -> None:
        """Start a requeued job now instead of after Slurm's hold of about two minutes
        (BeginTime). It must be PENDING first (a StartTime set while the requeue is still
        under way is overwritten), and a job relaunched within the second its previous
        run ended is refused ("Job credential revoked"): hence now+2."""
        self.wait(job, "PENDING", timeout=30)
        self.run("scontrol", "update", f"JobId={job}", "StartTime=now+2")

    def cancel_quietly(self, job: str) -> None:
        self.run("scancel", job, check=False)

    def history(self, job: str) -> list[str]:
        """Every end of every run of ``job`` from jobcomp (requeues included)."""
        path = self.logs / "jobcomp.txt"
        if not path.exists():
            return []
        keep = ("JobState", "ExitCode", "StartTime", "EndTime")
        lines = []
        for line in path.read_text().splitlines():
            rec = dict(kv.split("=", 1) for kv in line.split() if "=" in kv)
            if rec.get("JobId") == job.split("_")[0]:
                lines.append(" ".join(f"{k}={rec.get(k)}" for k in keep))
        return lines
