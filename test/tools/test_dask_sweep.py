"""The sweep on a Dask cluster started by hand: a scheduler and two dask-worker processes on
this machine. A sweep through --scheduler gives the same rows as a local run of the same config
and seeds, each naming the worker that ran it; a worker killed mid-run loses no run (its run is
redone on another worker); a killed client resumes; workers without the simulator or maps and
an unreachable scheduler are refused with a message naming the problem.
Run: GDRHCR_SIM=build/src/gdrhcr_sim python3 -m unittest discover -s test/tools"""
import contextlib
import csv
import io
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import unittest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tools"))
import gdrhcr_sweep  # noqa: E402

SIM = os.environ.get("GDRHCR_SIM", os.path.join(ROOT, "build", "src", "gdrhcr_sim"))

CONFIG = """
name: dask-test
steps: 30
seeds: 2
experiments:
  - map: maps/random-32-32-20.map
    tasks: random
    agents: [20, 40]
    planners:
      - {label: PIBT, planner: pibt}
      - {label: GD-RHCR, planner: gd-rhcr, node-budget: 2000}
"""
# Fields that depend on timing or on where a run ran; everything else must be identical.
VOLATILE = {"plan_time_mean_s", "plan_time_max_s", "step_wall_time_mean_s", "wall_time_s",
            "worker", "host"}


def rows_of(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def by_key(rows):
    return {gdrhcr_sweep.run_key(r): r for r in rows}


def dask_command(name):
    exe = shutil.which(name)
    if exe:
        return [exe]
    module = {"dask-scheduler": "distributed.cli.dask_scheduler",
              "dask-worker": "distributed.cli.dask_worker"}[name]
    return ["/usr/bin/python3", "-m", module]


class DaskSweepTest(unittest.TestCase):
    procs = []

    @classmethod
    def start(cls, cmd, log):
        p = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, start_new_session=True, cwd=cls.tmp)
        cls.procs.append(p)
        return p

    @classmethod
    def wait_for_workers(cls, n):
        from distributed import Client
        with Client(cls.address, timeout=60) as c:
            c.wait_for_workers(n, timeout=120)

    @classmethod
    def setUpClass(cls):
        cls.tmpdir = tempfile.TemporaryDirectory()
        cls.tmp = cls.tmpdir.name
        cls.log = open(os.path.join(cls.tmp, "dask.log"), "w")
        sched_file = os.path.join(cls.tmp, "scheduler.json")
        cls.start(dask_command("dask-scheduler") + ["--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                                                    "--scheduler-file", sched_file], cls.log)
        deadline = time.time() + 120
        while not os.path.exists(sched_file) and time.time() < deadline:
            time.sleep(0.1)
        time.sleep(0.2)  # the file is written in one go, but let it land
        with open(sched_file) as f:
            cls.address = json.load(f)["address"]
        cls.workers = {}
        for name in ("w1", "w2"):
            cls.workers[name] = cls.start_worker(name)
        cls.wait_for_workers(2)
        cls.cfg = os.path.join(cls.tmp, "c.yaml")
        with open(cls.cfg, "w") as f:
            f.write(CONFIG)
        # A simulator that first sleeps, so runs are still in flight when a process is killed.
        # It notes its pid and arguments, to find the run a worker is executing.
        cls.started = os.path.join(cls.tmp, "started")
        cls.delay_file = os.path.join(cls.tmp, "delay")  # seconds the wrapper sleeps
        cls.slow = os.path.join(cls.tmp, "slow_sim.sh")
        with open(cls.slow, "w") as f:
            f.write('#!/bin/sh\necho "$$ $*" >> %s\nsleep "$(cat %s)"\nexec %s "$@"\n'
                    % (cls.started, cls.delay_file, SIM))
        os.chmod(cls.slow, 0o755)
        # The reference: the same config run locally.
        cls.local_csv = os.path.join(cls.tmp, "local.csv")
        with contextlib.redirect_stdout(io.StringIO()):
            rc = gdrhcr_sweep.main([cls.cfg, "--out", cls.local_csv, "--jobs", "2", "--sim", SIM])
        assert rc == 0, "the local reference sweep failed"
        cls.reference = by_key(rows_of(cls.local_csv))
        assert len(cls.reference) == 8

    @classmethod
    def start_worker(cls, name):
        return cls.start(dask_command("dask-worker") + [cls.address, "--name", name, "--nthreads", "1",
                                                        "--no-dashboard"], cls.log)

    @classmethod
    def tearDownClass(cls):
        for p in cls.procs:
            if p.poll() is None:
                try:
                    os.killpg(p.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                p.wait()
        cls.log.close()
        cls.tmpdir.cleanup()

    def setUp(self):
        self.csv = os.path.join(self.tmp, "%s.csv" % self._testMethodName)
        if os.path.exists(self.started):
            os.remove(self.started)
        self.delay(0.4)

    def delay(self, seconds):
        with open(self.delay_file, "w") as f:
            f.write(str(seconds))

    def sweep_cmd(self, *extra):
        return ["/usr/bin/python3", os.path.join(ROOT, "tools", "gdrhcr_sweep.py"), self.cfg,
                "--out", self.csv, "--scheduler", self.address, "--sim", self.slow, *extra]

    def assert_same_as_local(self, rows):
        self.assertEqual(len(rows), 8)
        got = by_key(rows)
        self.assertEqual(set(got), set(self.reference))  # every run once
        for key, row in got.items():
            self.assertEqual(row["status"], "ok", row["error"])
            ref = self.reference[key]
            for field in gdrhcr_sweep.FIELDS:
                if field not in VOLATILE:
                    self.assertEqual(row[field], ref[field], "%s differs for %s" % (field, key))

    def test_scheduler_sweep_matches_local_run_and_names_workers(self):
        with contextlib.redirect_stdout(io.StringIO()) as out:
            rc = gdrhcr_sweep.main([self.cfg, "--out", self.csv, "--scheduler", self.address, "--sim", self.slow])
        self.assertEqual(rc, 0)
        rows = rows_of(self.csv)
        self.assert_same_as_local(rows)
        workers = {r["worker"] for r in rows}
        self.assertLessEqual(workers, {"w1", "w2"})
        self.assertEqual(workers, {"w1", "w2"}, "both idle workers should have been given runs")
        self.assertEqual({r["host"] for r in rows}, {socket.gethostname()})
        self.assertIn("8 to run on %s" % self.address, out.getvalue())
        self.assertTrue(all(r["worker"].startswith("local-") for r in self.reference.values()))

    def wait_for(self, cond, what, timeout=120):
        deadline = time.time() + timeout
        while time.time() < deadline:
            if cond():
                return
            time.sleep(0.05)
        self.fail("timed out waiting for " + what)

    def test_killed_worker_loses_no_run(self):
        w3 = self.start_worker("w3")
        self.wait_for_workers(3)
        self.delay(1.5)
        sweep = subprocess.Popen(self.sweep_cmd(), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)

        def w3_run():
            """Arguments of a run that w3 is executing (its wrapper is in w3's process group)."""
            if not os.path.exists(self.started):
                return None
            with open(self.started) as f:
                for line in f:
                    pid, args = line.split(" ", 1)
                    if "--map" not in args:
                        continue  # the start-up check's --help
                    try:
                        if os.getpgid(int(pid)) == w3.pid:
                            return args.split()
                    except ProcessLookupError:
                        pass
            return None

        self.wait_for(lambda: w3_run() is not None, "w3 to start a run")
        args = w3_run()
        os.killpg(w3.pid, signal.SIGKILL)  # the worker, its nanny and the run it was executing
        w3.wait()
        out, _ = sweep.communicate(timeout=300)
        self.assertEqual(sweep.returncode, 0, out)
        rows = rows_of(self.csv)
        self.assert_same_as_local(rows)
        agents, seed = args[args.index("--agents") + 1], args[args.index("--seed") + 1]
        planner = args[args.index("--planner") + 1]
        lost = [r for r in rows if r["agents"] == agents and r["seed"] == seed and r["planner"] == planner]
        self.assertEqual(len(lost), 1)
        self.assertIn(lost[0]["worker"], {"w1", "w2"}, "the killed worker's run was redone elsewhere")

    def test_killed_client_resumes(self):
        self.delay(1)
        client = subprocess.Popen(self.sweep_cmd(), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        self.wait_for(lambda: os.path.exists(self.csv) and len(rows_of(self.csv)) >= 2, "two rows")
        client.send_signal(signal.SIGKILL)
        client.wait()
        partial = len(rows_of(self.csv))
        self.assertLess(partial, 8, "the client was killed mid-sweep")
        self.delay(0)
        again = subprocess.run(self.sweep_cmd(), capture_output=True, text=True, timeout=300)
        self.assertEqual(again.returncode, 0, again.stdout + again.stderr)
        self.assertIn("%d already done, %d to run" % (partial, 8 - partial), again.stdout)
        self.assert_same_as_local(rows_of(self.csv))

    def test_workers_without_the_files_are_named(self):
        err = io.StringIO()
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            rc = gdrhcr_sweep.main([self.cfg, "--out", self.csv, "--scheduler", self.address,
                                    "--sim", SIM, "--worker-root", os.path.join(self.tmp, "no-checkout")])
        self.assertEqual(rc, 2)
        msg = err.getvalue()
        self.assertIn("worker w1", msg)
        self.assertIn("worker w2", msg)
        self.assertIn("no-checkout/maps/random-32-32-20.map is missing", msg)
        self.assertFalse(os.path.exists(self.csv) and len(rows_of(self.csv)) > 0)

    def test_unreachable_scheduler(self):
        s = socket.socket()
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
        s.close()  # nothing listens there now
        err = io.StringIO()
        with contextlib.redirect_stderr(err):
            rc = gdrhcr_sweep.main([self.cfg, "--out", self.csv, "--scheduler", "tcp://127.0.0.1:%d" % port,
                                    "--connect-timeout", "2", "--sim", SIM])
        self.assertEqual(rc, 2)
        self.assertIn("cannot reach the Dask scheduler at tcp://127.0.0.1:%d" % port, err.getvalue())


if __name__ == "__main__":
    unittest.main()
