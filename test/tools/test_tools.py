"""Tests of the experiment harness: the sweep's CSV and resumption (a killed sweep resumes
without duplicates), plots from a tiny CSV, and the group picture's partition.
Run: GDRHCR_SIM=build/src/gdrhcr_sim python3 -m unittest discover -s test/tools"""
import contextlib
import csv
import io
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
import unittest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tools"))
import gdrhcr_sweep  # noqa: E402
import plot_groups  # noqa: E402
import plot_sweep  # noqa: E402

SIM = os.environ.get("GDRHCR_SIM", os.path.join(ROOT, "build", "src", "gdrhcr_sim"))

CONFIG = """
name: test
steps: 30
seeds: 3
experiments:
  - map: maps/random-32-32-20.map
    tasks: random
    agents: [20, 40]
    planners:
      - {label: PIBT, planner: pibt}
      - {label: PIBT-mapd-no, planner: pibt, lookahead: 1}
"""


def rows_of(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


class SweepTest(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.cfg = os.path.join(self.tmp.name, "c.yaml")
        with open(self.cfg, "w") as f:
            f.write(CONFIG)
        self.csv = os.path.join(self.tmp.name, "out", "r.csv")

    def tearDown(self):
        self.tmp.cleanup()

    def sweep(self, *extra):
        return gdrhcr_sweep.main([self.cfg, "--out", self.csv, "--jobs", "2", "--sim", SIM, *extra])

    def test_expand_counts_and_k_threshold_rule(self):
        cfg = {"steps": 10, "seeds": [4, 5], "experiments": [
            {"map": "m", "agents": [10, 300], "planners": [
                {"label": "G", "planner": "gd-rhcr", "k_threshold_fraction": 0.1, "k_threshold_cap": 20}]}]}
        runs = gdrhcr_sweep.expand(cfg)
        self.assertEqual(len(runs), 4)
        self.assertEqual({r["options"]["k-threshold"] for r in runs if r["agents"] == 10}, {2})
        self.assertEqual({r["options"]["k-threshold"] for r in runs if r["agents"] == 300}, {20})

    def test_full_sweep_writes_every_run_once(self):
        self.assertEqual(self.sweep(), 0)
        rows = rows_of(self.csv)
        self.assertEqual(len(rows), 12)
        self.assertEqual(len({gdrhcr_sweep.run_key(r) for r in rows}), 12)
        for r in rows:
            self.assertEqual(r["status"], "ok")
            self.assertEqual(r["collisions"], "0")
            self.assertGreater(float(r["throughput"]), 0)
            self.assertIn(r["worker"], {"local-0", "local-1"})  # the local cluster's --jobs 2 workers
        # A second run has nothing left to do and adds nothing.
        self.assertEqual(self.sweep(), 0)
        self.assertEqual(len(rows_of(self.csv)), 12)

    def test_resume_after_partial_run_and_torn_line(self):
        self.assertEqual(self.sweep("--limit", "5"), 0)
        self.assertEqual(len(rows_of(self.csv)), 5)
        with open(self.csv, "a") as f:
            f.write("PIBT,maps/random-32-32-20.map,random,20,9,30,te")  # a kill mid-write
        self.assertEqual(self.sweep(), 0)
        rows = rows_of(self.csv)
        self.assertEqual(len(rows), 12)
        self.assertEqual(len({gdrhcr_sweep.run_key(r) for r in rows}), 12)

    def test_killed_sweep_resumes_without_duplicates(self):
        cmd = [sys.executable, os.path.join(ROOT, "tools", "gdrhcr_sweep.py"), self.cfg,
               "--out", self.csv, "--jobs", "1", "--sim", SIM]
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.time() + 60
        while time.time() < deadline:
            if os.path.exists(self.csv) and len(rows_of(self.csv)) >= 2:
                break
            time.sleep(0.02)
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        partial = len(rows_of(self.csv))
        self.assertGreaterEqual(partial, 2)
        self.assertEqual(self.sweep(), 0)
        rows = rows_of(self.csv)
        self.assertEqual(len(rows), 12)
        self.assertEqual(len({gdrhcr_sweep.run_key(r) for r in rows}), 12)

    def test_csv_without_worker_column_is_resumed(self):
        # A CSV written before the worker and host columns existed: its finished rows count.
        self.assertEqual(self.sweep("--limit", "4"), 0)
        old = [f for f in gdrhcr_sweep.FIELDS if f not in ("worker", "host")]
        rows = rows_of(self.csv)
        with open(self.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=old, extrasaction="ignore")
            w.writeheader()
            w.writerows(rows)
        self.assertEqual(self.sweep(), 0)
        rows = rows_of(self.csv)
        self.assertEqual(len(rows), 12)
        self.assertEqual(len({gdrhcr_sweep.run_key(r) for r in rows}), 12)
        self.assertEqual(sum(1 for r in rows if r["worker"] == ""), 4)  # the 4 old rows kept, not redone

    def test_foreign_csv_is_refused(self):
        os.makedirs(os.path.dirname(self.csv))
        with open(self.csv, "w") as f:
            f.write("a,b\n1,2\n")
        self.assertEqual(self.sweep(), 2)
        with open(self.csv) as f:
            self.assertEqual(f.read(), "a,b\n1,2\n")  # untouched

    def test_planner_agent_counts(self):
        cfg = {"seeds": 1, "experiments": [
            {"map": "m", "agents": [10, 20, 30], "planners": [
                {"label": "A", "planner": "pibt"}, {"label": "B", "planner": "rhcr", "agents": [10]}]}]}
        runs = gdrhcr_sweep.expand(cfg)
        self.assertEqual(sorted((r["label"], r["agents"]) for r in runs),
                         [("A", 10), ("A", 20), ("A", 30), ("B", 10)])
        self.assertNotIn("agents", runs[-1]["options"])

    def test_selecting_part_of_a_config(self):
        self.assertEqual(self.sweep("--seeds", "1", "--labels", "PIBT", "--agents", "40"), 0)
        rows = rows_of(self.csv)
        self.assertEqual([(r["label"], r["agents"], r["seed"]) for r in rows], [("PIBT", "40", "0")])
        self.assertEqual(self.sweep("--seeds", "1,2", "--maps", "random-32-32-20"), 0)
        self.assertEqual(len(rows_of(self.csv)), 1 + 2 * 4)  # the first row kept, not redone
        self.assertEqual(self.sweep("--labels", "RHCR"), 2)  # not in the config: an error

    def test_bad_config_and_missing_simulator(self):
        with open(self.cfg, "w") as f:
            f.write("steps: 3\n")
        self.assertEqual(gdrhcr_sweep.main([self.cfg, "--out", self.csv, "--sim", SIM]), 2)
        with open(self.cfg, "w") as f:
            f.write(CONFIG)
        self.assertEqual(gdrhcr_sweep.main([self.cfg, "--out", self.csv, "--sim", "/no/such/sim"]), 2)

    def test_failed_runs_are_recorded_and_retried(self):
        with open(self.cfg, "w") as f:
            f.write(CONFIG.replace("lookahead: 1", "lookahead: 0"))  # invalid: rejected by the sim
        self.assertEqual(self.sweep(), 1)
        rows = rows_of(self.csv)
        bad = [r for r in rows if r["status"] != "ok"]
        self.assertEqual(len(bad), 6)
        self.assertIn("lookahead", bad[0]["error"])


class PlotTest(unittest.TestCase):
    def test_plots_from_tiny_csv(self):
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "t.csv")
            with open(path, "w", newline="") as f:
                w = csv.DictWriter(f, fieldnames=gdrhcr_sweep.FIELDS)
                w.writeheader()
                for label in ("GD-RHCR", "PIBT", "V=2", "V=4"):
                    for agents in (10, 20):
                        for seed in (0, 1):
                            row = {k: "" for k in gdrhcr_sweep.FIELDS}
                            row.update(label=label, map="maps/x.map", tasks="random", agents=agents,
                                       seed=seed, steps=50, status="ok", throughput=agents / 10 + seed,
                                       plan_time_mean_s=0.001 * agents, wall_time_s=1 + seed)
                            if label != "PIBT":
                                row.update(groups_mean_count=agents / 2, groups_mean_size=2, groups_mean_max_size=4)
                            w.writerow(row)
            out = os.path.join(tmp, "figs")
            self.assertEqual(plot_sweep.main([path, "--out", out]), 0)
            for name in ("x_throughput.png", "x_plan_time.png", "x_wall_time.png", "x_groups.png", "x_ablation.png"):
                p = os.path.join(out, name)
                self.assertTrue(os.path.exists(p), name)
                with open(p, "rb") as f:
                    self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")
            paper = os.path.join(tmp, "paper")
            with contextlib.redirect_stdout(io.StringIO()) as out:
                self.assertEqual(plot_sweep.main([path, "--out", paper, "--paper", "fam", "--markdown"]), 0)
            for name in ("fam.png", "fam_wall.png", "fam_groups.png"):
                with open(os.path.join(paper, name), "rb") as f:
                    self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")
            table = out.getvalue()
            self.assertIn("| x | 10 | 2 | 1.500 ± 0.707 |", table)  # GD-RHCR first: agents/10 + seed
            kept = plot_sweep.keep_min_seeds(plot_sweep.load(path)[:-1], 2)  # the last row: V=4, 20 agents, seed 1
            self.assertEqual(len(kept), 4 * 2 * 2 - 2)
            self.assertNotIn(("V=4", "20"), {(r["label"], r["agents"]) for r in kept})
            data = plot_sweep.series(plot_sweep.load(path), "throughput")
            self.assertAlmostEqual(data["PIBT"][0][1], 1.5)  # mean of 1.0 and 2.0
            self.assertAlmostEqual(data["PIBT"][0][2], 0.7071067811865476)  # sample SD


class GroupPictureTest(unittest.TestCase):
    def test_partition_respects_walls(self):
        rows = [".@...", ".@...", "....."]
        comp, links = plot_groups.groups(rows, [(0, 0), (2, 0), (3, 0)], 2)
        self.assertNotEqual(comp[0], comp[1])  # 6 apart around the wall
        self.assertEqual(comp[1], comp[2])
        self.assertEqual(links, [(1, 2)])


def canonical(key):
    """A parameter's name as the core reads it (Params::canonical): '_' as '-', lower case past one letter."""
    key = key.replace("_", "-") if len(key) > 1 else key
    return key.lower() if len(key) > 1 else key


def sim_help():
    """`gdrhcr_sim --help` and its parameter rows: {planner: {name: (range, default)}}."""
    out = subprocess.run([SIM, "--help"], capture_output=True, text=True, check=True).stdout
    rows, planner = {}, None
    for line in out.splitlines():
        if line.startswith("--planner "):
            planner = line.split()[1]
            rows[planner] = {}
        elif planner and line.startswith("  --"):
            name, rest = line[4:].split(" ", 1)
            rng, default = rest.split(", default ", 1)
            rows[planner][name] = (rng, default.split(":", 1)[0])
    return out, rows


class ExperimentConfigTest(unittest.TestCase):
    """Every planner option in config/experiments/*.yaml is a parameter of that planner in the
    parameter table (as `gdrhcr_sim --help` lists it), so a sweep never dies on a misspelt one."""

    def test_experiment_configs_use_known_parameters(self):
        known = sim_help()[1]
        self.assertEqual(sorted(known), ["gd-rhcr", "pibt", "rhcr"])
        configs = sorted(f for f in os.listdir(os.path.join(ROOT, "config", "experiments")) if f.endswith(".yaml"))
        self.assertGreater(len(configs), 3)
        for name in configs:
            runs = gdrhcr_sweep.expand(gdrhcr_sweep.load_config(os.path.join(ROOT, "config", "experiments", name)))
            for run in runs:
                opts = dict(run["options"])
                planner = opts.pop("planner", "pibt")
                for key in opts:
                    self.assertIn(canonical(key), known[planner], "%s: %s has no parameter %s" % (name, planner, key))


class ParameterTableConsumersTest(unittest.TestCase):
    """The README's parameter list and dynamic_reconfigure's cfg/Planner.cfg come from the
    parameter table (as `gdrhcr_sim --help` prints it)."""

    def test_readme_parameter_list_is_the_tables(self):
        out, _ = sim_help()
        made = subprocess.run([sys.executable, os.path.join(ROOT, "tools", "readme_params.py")], input=out,
                              capture_output=True, text=True, check=True).stdout.strip()
        with open(os.path.join(ROOT, "README.md")) as f:
            readme = f.read()
        start = readme.index("<!-- planner parameters -->")
        end = readme.index("<!-- /planner parameters -->") + len("<!-- /planner parameters -->")
        self.assertEqual(readme[start:end].strip(), made,
                         "README's list is stale: build/src/gdrhcr_sim --help | python3 tools/readme_params.py")

    def test_reconfigure_planner_parameters_are_the_tables(self):
        _, rows = sim_help()
        with open(os.path.join(ROOT, "gd_rhcr_planner", "cfg", "Planner.cfg")) as f:
            cfg = f.read()
        found = re.findall(r'planner\.add\("(\w+)", (\w+), 0, "[^"]*", ([^,]+), ([^,]+), ([^,)]+)\)', cfg)
        self.assertEqual(sorted(f[0] for f in found), ["H", "K_threshold", "V", "c_soft"])
        for name, _, default, lo, hi in found:
            canon = canonical(name)
            rng, table_default = rows["gd-rhcr"][canon]
            tlo, thi = (float(x) for x in rng.strip("[]").split(", "))
            if canon == "k-threshold":
                self.assertEqual(float(default), 0, "0 = the planner's rule")
                self.assertTrue(table_default.startswith("rule"))
            else:
                self.assertEqual(float(default), float(table_default), name)
            # wider than the table's range: out-of-range values reach the node, which rejects them
            self.assertLessEqual(float(lo), tlo, name)
            self.assertGreaterEqual(float(hi), thi, name)
        solver = re.search(r'planner\.add\("solver", str_t, 0, "[^"]*", "(\w+)"', cfg)
        self.assertIsNotNone(solver)
        self.assertEqual(solver.group(1), rows["gd-rhcr"]["solver"][1])
        self.assertNotIn("solver2", cfg)


if __name__ == "__main__":
    unittest.main()
