"""tools/bench_lorr.py on the small LoRR instance (test/lorr/small, 20 steps, one budget): the
Start-Kit's run is valid, the row carries its count and our own time per step within the budget,
the JSON and the plot are written, and bad arguments are refused naming them.
Needs the LoRR Start-Kit v1.1.5 (as scripts/lorr_test.sh: LORR_START_KIT or ../shared/lorr)."""
import contextlib
import io
import json
import os
import sys
import tempfile
import unittest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tools"))
import bench_lorr  # noqa: E402

SMALL = os.path.join(ROOT, "test", "lorr", "small", "small.json")


def read_json(path):
    with open(path) as f:
        return json.load(f)


class BenchLorrTest(unittest.TestCase):
    def setUp(self):
        self.kit = os.environ.get("LORR_START_KIT") or bench_lorr.default_start_kit()
        self.assertTrue(self.kit, "no LoRR Start-Kit found; set LORR_START_KIT to the Start-Kit v1.1.5 directory")

    def test_small_instance_row_json_and_plot(self):
        with tempfile.TemporaryDirectory() as tmp:
            out_json, png = os.path.join(tmp, "curve.json"), os.path.join(tmp, "curve.png")
            with contextlib.redirect_stdout(io.StringIO()) as printed:
                self.addCleanup(os.environ.pop, "GDRHCR_PREP_DIR", None)
                rc = bench_lorr.main(["--start-kit", self.kit, "--steps", "20", "--budgets", "50",
                                      "--out-dir", tmp, "--json", out_json, "--plot", png,
                                      "--prep-dir", os.path.join(tmp, "prep"), SMALL])
            self.assertEqual(rc, 0, printed.getvalue())
            rows = read_json(out_json)["rows"]
            self.assertEqual(len(rows), 1)
            row = rows[0]
            self.assertEqual((row["instance"], row["steps"], row["budget_ms"]), ("small", 20, 50))
            self.assertEqual(row["all_valid"], "Yes")
            self.assertEqual(row["errors"], 0)
            self.assertGreater(row["errands"], 0)
            self.assertEqual(row["errands"], read_json(row["output"])["numTaskFinished"])
            with open(row["output"][: -len(".json")] + ".times") as f:
                times = f.read().split()
            self.assertEqual(len(times), 20)  # one line per step
            self.assertLessEqual(row["ms_p99"], 50)
            self.assertIn("small", printed.getvalue())
            # Where the errands' steps went, from the Start-Kit's own paths and events.
            e = row["errand_steps"]
            self.assertEqual(e["errands"], row["errands"])
            self.assertAlmostEqual(e["steps_per_errand"],
                                   e["forward_per_errand"] + e["turns_per_errand"] + e["waits_per_errand"])
            self.assertGreaterEqual(e["forward_per_errand"], 1)
            self.assertIn("per errand:", printed.getvalue())
            self.assertTrue(os.path.getsize(png) > 0)
            # The offline preparation was made in the run's preprocessing and cached.
            self.assertIn(row["prep_traffic_cost"], (0.0, 2.0))
            self.assertEqual(len([f for f in os.listdir(os.path.join(tmp, "prep")) if f.startswith("gdrhcr-prep-")]), 1)

    def test_errand_steps_split_the_actions_between_assignment_and_finish(self):
        output = {"actualPaths": ["F,R,F,W,F,C,W", "W,W"],
                  "events": [[[0, 0, "assigned"], [0, 4, "finished"], [2, 4, "assigned"], [2, 6, "finished"],
                              [3, 6, "assigned"]],
                             [[1, 0, "assigned"]]]}
        e = bench_lorr.errand_steps(output)
        # Task 0: F R F W (2 forward, 1 turn, 1 wait); task 2: F C; task 3 and task 1 unfinished.
        self.assertEqual(e["errands"], 2)
        self.assertEqual(e["steps_per_errand"], 3.0)
        self.assertEqual(e["forward_per_errand"], 1.5)
        self.assertEqual(e["turns_per_errand"], 1.0)
        self.assertEqual(e["waits_per_errand"], 0.5)
        self.assertEqual(bench_lorr.errand_steps({})["errands"], 0)

    def test_bad_arguments_are_named(self):
        for args, word in ((["--budgets", "0", SMALL], "--budgets"), (["--steps", "0", SMALL], "--steps"),
                           ([SMALL], "--steps"), (["--steps", "5", "/nonexistent.json"], "/nonexistent.json"),
                           (["--start-kit", "/tmp", SMALL], "--start-kit")):
            err = io.StringIO()
            with contextlib.redirect_stderr(err), self.assertRaises(SystemExit) as e:
                bench_lorr.main((["--start-kit", self.kit] if "--start-kit" not in args else []) + args)
            self.assertEqual(e.exception.code, 2)
            self.assertIn(word, err.getvalue())


if __name__ == "__main__":
    unittest.main()
