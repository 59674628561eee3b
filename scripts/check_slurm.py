"""The Slurm job-array recipe of docs/sweeps.md, run for real on a single-node Slurm cluster.

Starts munged, slurmctld and slurmd on localhost (Debian's slurm-wlm and munge; a temporary
key, state, spool and free ports, nothing under /etc), then:

1. submits the recipe's job array (the shell block under "On a cluster" in docs/sweeps.md, with
   the sweep, results directory, array size and CPUs of this small sweep put in) and its merge
   job (`sbatch --dependency=afterok:<array job id>`, the documented command), and checks the
   merged rows equal those of the same sweep run in one process;
2. submits it again into a new directory, one task at a time, cancels the last shard's task
   (`scancel`, as a pre-emption does) once it has written a cell, checks that the merge job never
   starts, that only whole cells are left and no summary, then resubmits that task alone as the
   docs say, with the merge after it: its finished cells are kept, and the merged rows again
   equal the one-process sweep's.

Needs root (slurmd starts jobs as their user). The daemons are stopped when the check ends,
and any left by an interrupted earlier run of this check are stopped when it starts.
"""
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

from physid_common import ROOT, Report, arguments, physid_bin

PREFIX = "physid-slurm-"  # the temporary directory's prefix, how leftover daemons are found
SAMPLE_SIZE = os.path.join(ROOT, "scenarios", "sample_size.toml")
SHARDS = 3
SWEEP = """scenario = "{base}"
[grid]
"sensors.torque_noise" = [0.3, 2.0]
[experiment]
seeds = 8
sizes = [30, 300, 3000]
validation = 3000
constraints = ["none", "ellipsoid"]
"""
CELLS = 2 * 8


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def stop_leftovers():
    """Stops daemons left by an interrupted earlier run of this check (their command lines name
    its directory) and removes its directory."""
    for pid in os.listdir("/proc"):
        if not pid.isdigit():
            continue
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                cmd = f.read().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if PREFIX in cmd and re.search(r"\b(munged|slurmctld|slurmd)\b", cmd):
            try:
                os.kill(int(pid), signal.SIGKILL)
            except OSError:
                pass
    tmp = tempfile.gettempdir()
    for name in os.listdir(tmp):
        if name.startswith(PREFIX):
            shutil.rmtree(os.path.join(tmp, name), ignore_errors=True)


SLURM_CONF = """ClusterName=physid
SlurmctldHost=localhost
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket={d}/munge.sock
SlurmctldPort={ctld_port}
SlurmdPort={d_port}
StateSaveLocation={d}/state
SlurmdSpoolDir={d}/spool
SlurmctldPidFile={d}/slurmctld.pid
SlurmdPidFile={d}/slurmd.pid
SlurmctldLogFile={d}/slurmctld.log
SlurmdLogFile={d}/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SwitchType=switch/none
MpiDefault=none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
InactiveLimit=0
KillWait=5
MinJobAge=600
NodeName=localhost CPUs={cpus} RealMemory=1000 State=UNKNOWN
PartitionName=debug Nodes=localhost Default=YES MaxTime=INFINITE State=UP
"""


class Cluster:
    """A single-node Slurm cluster in directory `d` (munge, controller and node daemon)."""

    def __init__(self, d):
        self.d = d
        os.makedirs(f"{d}/state")
        os.makedirs(f"{d}/spool")
        with open(f"{d}/munge.key", "wb") as f:
            f.write(os.urandom(1024))
        os.chmod(f"{d}/munge.key", 0o600)
        with open(f"{d}/slurm.conf", "w") as f:
            f.write(SLURM_CONF.format(d=d, ctld_port=free_port(), d_port=free_port(),
                                      cpus=os.cpu_count() or 1))
        self.env = dict(os.environ, SLURM_CONF=f"{d}/slurm.conf")

    def start(self):
        d = self.d
        self.daemon(["munged", "--force", f"--key-file={d}/munge.key", f"--socket={d}/munge.sock",
                     f"--pid-file={d}/munged.pid", f"--log-file={d}/munged.log",
                     f"--seed-file={d}/munged.seed"])
        self.daemon(["slurmctld", "-f", f"{d}/slurm.conf"])
        self.daemon(["slurmd", "-f", f"{d}/slurm.conf", "-N", "localhost"])
        deadline = time.time() + 120
        while time.time() < deadline:
            state = self.out(["sinfo", "-h", "-o", "%T"], check=False).strip()
            if state == "idle":
                return
            time.sleep(0.5)
        sys.exit(f"the Slurm node did not become idle in 120 s (last state '{state}'); "
                 f"see {d}/slurmctld.log and {d}/slurmd.log")

    def daemon(self, cmd):
        res = subprocess.run(cmd, env=self.env, capture_output=True, text=True)
        if res.returncode != 0:
            sys.exit(f"{' '.join(cmd)} did not start:\n{res.stderr}")

    def stop(self):
        """Stops the daemons: SIGTERM, then SIGKILL to any still running 3 s later."""
        for name in ("slurmd", "slurmctld", "munged"):
            try:
                with open(f"{self.d}/{name}.pid") as f:
                    pid = int(f.read().split()[0])
                os.kill(pid, signal.SIGTERM)
            except (OSError, ValueError, IndexError):
                continue
            deadline = time.time() + 3
            while os.path.exists(f"/proc/{pid}") and time.time() < deadline:
                time.sleep(0.05)
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass

    def out(self, cmd, check=True):
        res = subprocess.run(cmd, env=self.env, capture_output=True, text=True)
        if check and res.returncode != 0:
            sys.exit(f"{' '.join(cmd)} failed:\n{res.stderr}")
        return res.stdout

    def submit(self, *args):
        """`sbatch --parsable ARGS` run in the cluster's directory (its output files there too,
        never in the caller's working directory): the job id."""
        where = [f"--chdir={self.d}"] + ([] if "-o" in args else ["-o", f"{self.d}/slurm-%j.out"])
        return self.out(["sbatch", "--parsable", *where, *args]).strip().split(";")[0]

    def states(self, job):
        """{job id or array task id: state} of a job (an array's tasks each by their id)."""
        text = self.out(["scontrol", "-o", "show", "job", job], check=False)
        found = {}
        for line in text.splitlines():
            fields = dict(kv.split("=", 1) for kv in line.split() if "=" in kv)
            task = fields.get("ArrayTaskId")
            key = f"{fields.get('ArrayJobId')}_{task}" if task else fields.get("JobId")
            found[key] = (fields.get("JobState"), fields.get("Reason"))
        return found

    def wait(self, job, timeout=300):
        """Waits until no task of `job` is pending or running; returns their final states."""
        deadline = time.time() + timeout
        while time.time() < deadline:
            states = self.states(job)
            if states and all(s not in ("PENDING", "RUNNING", "CONFIGURING", "COMPLETING")
                              for s, _ in states.values()):
                return states
            time.sleep(0.3)
        sys.exit(f"job {job} did not finish in {timeout} s: {self.states(job)}")


def recipe(binary, sweep, out, shards, path):
    """docs/sweeps.md's job-array script for this sweep, written to `path`, and its merge
    command; or exits naming what of the recipe was not found."""
    with open(os.path.join(ROOT, "docs", "sweeps.md")) as f:
        doc = f.read()
    section = doc[doc.index("## On a cluster"):]
    script, merge = re.findall(r"```sh\n(.*?)```", section, re.S)[:2]
    swaps = [("scenarios/sweeps/noise.toml", sweep), ("/shared/results/noise", out),
             ("--array=0-63", f"--array=0-{shards - 1}"), ("/64 ", f"/{shards} "),
             ("--cpus-per-task=4", "--cpus-per-task=1")]
    for old, new in swaps:
        if old not in script:
            sys.exit(f"docs/sweeps.md's job-array script no longer has '{old}': update this check")
        script = script.replace(old, new)
        merge = merge.replace(old, new)
    call = lambda text: re.sub(r"^physid ", f"'{binary}' ", text, flags=re.M)
    with open(path, "w") as f:
        f.write(call(script))
    return call(merge).strip()


def rows(out):
    """rows.csv without its last column (the wall-clock solve time)."""
    with open(os.path.join(out, "rows.csv")) as f:
        return [line.rstrip("\n").rsplit(",", 1)[0] for line in f]


def cells(out):
    d = os.path.join(out, "cells")
    return sorted(os.listdir(d)) if os.path.isdir(d) else []


def run_array(cluster, report, binary, sweep, out, reference):
    """Run 1: the recipe's array and its merge job; rows equal the one-process sweep's."""
    path = os.path.join(cluster.d, "array.sh")
    merge = recipe(binary, sweep, out, SHARDS, path)
    logs = os.path.join(cluster.d, "run1_%A_%a.log")
    array = cluster.submit("-o", logs, path)
    merged = cluster.submit(f"--dependency=afterok:{array}", "-o", f"{cluster.d}/merge1.log",
                            "--wrap", merge)
    tasks = cluster.wait(array)
    report.check(f"the recipe's array of {SHARDS} tasks completed: {sorted(s for s, _ in tasks.values())}",
                 len(tasks) == SHARDS and all(s == "COMPLETED" for s, _ in tasks.values()))
    state = cluster.wait(merged)
    report.check(f"the merge job (afterok) ran after the array: {list(state.values())}",
                 all(s == "COMPLETED" for s, _ in state.values()))
    same = os.path.exists(os.path.join(out, "summary.md")) and rows(out) == reference
    report.check(f"the merged rows.csv ({len(reference) - 1} rows) equals the one-process sweep's", same)


def run_killed(cluster, report, binary, sweep, out, reference):
    """Run 2: one task cancelled after its first cell, resubmitted alone, then merged."""
    path = os.path.join(cluster.d, "array2.sh")
    merge = recipe(binary, sweep, out, 2, path)
    array = cluster.submit("-o", os.path.join(cluster.d, "run2_%A_%a.log"), path)
    merged = cluster.submit(f"--dependency=afterok:{array}", "--wrap", merge)
    deadline = time.time() + 120
    while not any(int(c[:4]) % 2 == 1 for c in cells(out) if c.endswith(".parquet")):
        if time.time() > deadline:
            sys.exit(f"shard 1 wrote no cell in 120 s: {cluster.states(array)}")
        time.sleep(0.01)
    cluster.out(["scancel", f"{array}_1"])
    tasks = cluster.wait(array)
    kept = [c for c in cells(out) if c.endswith(".parquet")]
    report.check(f"shard 1 cancelled mid-run ({tasks.get(f'{array}_1')}), {len(kept)} of {CELLS} cells kept",
                 tasks.get(f"{array}_1", ("",))[0] == "CANCELLED" and len(kept) < CELLS)
    time.sleep(1.0)  # the controller marks the dependency as never satisfied at its next pass
    state = cluster.states(merged).get(merged, ("", ""))
    report.check(f"the merge job did not start after the cancelled array: {state}",
                 state[0] == "PENDING" and "Dependency" in (state[1] or "")
                 and not os.path.exists(os.path.join(out, "summary.md")))
    cluster.out(["scancel", merged])
    # Every file a killed run left is either a whole cell or not named as one.
    import pyarrow.parquet as pq
    whole = all(pq.read_table(os.path.join(out, "cells", c)).num_rows > 0 for c in kept)
    report.check("every cell file left by the cancelled task is a whole table", whole)
    again = cluster.submit("--array=1", "-o", os.path.join(cluster.d, "resub_%A_%a.log"), path)
    merged = cluster.submit(f"--dependency=afterok:{again}", "--wrap", merge)
    cluster.wait(again)
    cluster.wait(merged)
    with open(os.path.join(cluster.d, f"resub_{again}_1.log")) as f:
        log = f.read()
    done = re.search(r"in shard 1/2 of \d+, (\d+) already done, (\d+) to run", log)
    report.check(f"the resubmitted task kept its shard's finished cells: '{done and done.group(0)}'",
                 done is not None and int(done.group(1)) >= 1)
    same = os.path.exists(os.path.join(out, "summary.md")) and rows(out) == reference
    report.check("after the resubmission, the merged rows.csv equals the one-process sweep's", same)


def main():
    binary = os.path.abspath(physid_bin(arguments(__doc__).physid))
    report = Report("check_slurm")
    if os.geteuid() != 0:
        sys.exit("check_slurm: needs root (slurmd starts jobs as their user): run as root")
    for tool in ("munged", "slurmctld", "slurmd", "sbatch"):
        if shutil.which(tool) is None:
            sys.exit(f"check_slurm: no {tool} on PATH: apt-get install slurm-wlm munge")
    stop_leftovers()
    d = tempfile.mkdtemp(prefix=PREFIX)
    os.chmod(d, 0o755)
    cluster = Cluster(d)
    try:
        sweep = os.path.join(d, "sweep.toml")
        with open(sweep, "w") as f:
            f.write(SWEEP.format(base=SAMPLE_SIZE))
        one = os.path.join(d, "one")
        subprocess.run([binary, "sweep", sweep, "--out", one, "--threads", "2"], check=True,
                       capture_output=True)
        reference = rows(one)
        t0 = time.time()
        cluster.start()
        print(f"single-node Slurm cluster up in {time.time() - t0:.1f} s ({d})")
        run_array(cluster, report, binary, sweep, os.path.join(d, "array"), reference)
        run_killed(cluster, report, binary, sweep, os.path.join(d, "killed"), reference)
    finally:
        cluster.stop()
        if all(report.rows):
            shutil.rmtree(d, ignore_errors=True)
    report.finish()


if __name__ == "__main__":
    main()
