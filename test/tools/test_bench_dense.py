"""tools/bench_dense.py --budget-curve on a small setting (20 agents, 10 steps): a PIBT row and a
GD-RHCR row per budget in each action model, each run in the model it names with the budget it
names (read back from the simulator's own parameters), goals reached, and bad settings or
budgets refused naming them. Figures only, no timing asserted."""
import contextlib
import io
import json
import os
import sys
import tempfile
import unittest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tools"))
import bench_dense  # noqa: E402

SIM = os.environ.get("GDRHCR_SIM", os.path.join(ROOT, "build", "src", "gdrhcr_sim"))


class BudgetCurveTest(unittest.TestCase):
    def test_rows_per_model_and_budget(self):
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "curve.json")
            with contextlib.redirect_stdout(io.StringIO()):
                bench_dense.main(["--sim", SIM, "--budget-curve", "--steps", "10", "--settings", "random-32-32-20:20",
                                  "--budgets", "20", "200", "--json", out])
            with open(out) as f:
                rows = json.load(f)["rows"]
        got = [(r["action_model"], r["planner"], r["budget_ms"]) for r in rows]
        self.assertEqual(got, [(m, p, b) for m in ("mapf", "rotation")
                               for p, b in (("PIBT", None), ("GD-RHCR", 20.0), ("GD-RHCR", 200.0))])
        for r in rows:
            self.assertEqual(r["params"]["action_model"], r["action_model"])
            if r["budget_ms"] is not None:
                self.assertAlmostEqual(r["params"]["step_budget"], r["budget_ms"] / 1000)
            self.assertGreater(r["throughput"], 0, r)
            self.assertLessEqual(r["throughput"], r["free_flow"] + 1e-9, r)

    def test_bad_settings_and_budgets_are_named(self):
        for argv, word in ((["--settings", "random-32-32-20"], "random-32-32-20"),
                           (["--settings", "no-such-map:10"], "no-such-map"),
                           (["--budgets", "0"], "--budgets")):
            with self.assertRaises(SystemExit) as e, contextlib.redirect_stdout(io.StringIO()):
                bench_dense.main(["--sim", SIM, "--budget-curve", "--steps", "5"] + argv)
            self.assertIn(word, str(e.exception))


if __name__ == "__main__":
    unittest.main()
