"""tools/jam_report.py on a hand-made 5 x 3 map and four agents' paths, whose figures are worked
out by hand: the moving share, how long agents have stood, clusters of touching agents, the
density of blocks; then a real run of gdrhcr_sim read back; bad input refused naming it."""
import contextlib
import io
import json
import os
import subprocess
import sys
import tempfile
import unittest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tools"))
import jam_report  # noqa: E402

SIM = os.environ.get("GDRHCR_SIM", os.path.join(ROOT, "build", "src", "gdrhcr_sim"))

MAP = "type octile\nheight 3\nwidth 5\nmap\n.....\n.@...\n.....\n"
# Agent 0 moves every step, 1 and 3 stand, 2 moves once (steps 1 -> 2).
PATHS = ("0: (0,0),(1,0),(2,0),(3,0),\n1: (4,2),(4,2),(4,2),(4,2),\n"
         "2: (0,2),(0,2),(1,2),(1,2),\n3: (3,1),(3,1),(3,1),(3,1),\n")


def run(tmp, map_text, paths_text, *args):
    with open(os.path.join(tmp, "m.map"), "w") as f:
        f.write(map_text)
    with open(os.path.join(tmp, "p.txt"), "w") as f:
        f.write(paths_text)
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = jam_report.main(["--map", os.path.join(tmp, "m.map"), "--paths", os.path.join(tmp, "p.txt"),
                                "--json", os.path.join(tmp, "r.json"), *args])
    return code, out.getvalue(), err.getvalue()


class JamReportTest(unittest.TestCase):
    def test_figures_of_a_hand_made_run(self):
        with tempfile.TemporaryDirectory() as tmp:
            code, out, _ = run(tmp, MAP, PATHS, "--at", "2", "--window", "3", "--block", "2")
            self.assertEqual(code, 0)
            with open(os.path.join(tmp, "r.json")) as f:
                r = json.load(f)
        self.assertEqual((r["agents"], r["steps"]), (4, 3))
        self.assertEqual(r["moving_share"], [[0, 2, 4 / 12]])  # 3 + 0 + 1 + 0 moves in 12 agent-steps
        at = r["at"][0]
        self.assertEqual((at["step"], at["stood_5"], at["stood_20"]), (2, 0, 0))
        # (2,0), (3,1) and (4,2) touch diagonally; (1,2) is alone.
        self.assertEqual(at["clusters"], [[3, 2, 0, 4, 2], [1, 1, 2, 1, 2]])
        # 2 x 2 blocks: (2..3, 0..1) has 4 free cells and 2 agents; (4, 2) one free cell, one agent.
        self.assertEqual(at["density"], [".5.", "5.9"])
        self.assertIn("moved in 33% of agent-steps", out)
        self.assertIn("cluster of 3 touching agents in x 2-4, y 0-2", out)

    def test_standing_counts_the_steps_in_the_same_cell(self):
        paths = [[(0, 0)] * 6, [(0, 0), (1, 0), (1, 0), (1, 0), (2, 0), (2, 0)]]
        self.assertEqual(jam_report.standing(paths, 5), [5, 1])
        self.assertEqual(jam_report.standing(paths, 3), [3, 2])

    def test_a_simulated_run(self):
        with tempfile.TemporaryDirectory() as tmp:
            paths = os.path.join(tmp, "p.txt")
            subprocess.run([SIM, "--map", os.path.join(ROOT, "maps", "random-32-32-20.map"), "--agents", "60",
                            "--steps", "30", "--seed", "1", "--planner", "pibt", "--quiet", "--out",
                            os.path.join(tmp, "r.json"), "--paths", paths], check=True)
            out = io.StringIO()
            with contextlib.redirect_stdout(out):
                code = jam_report.main(["--map", os.path.join(ROOT, "maps", "random-32-32-20.map"), "--paths", paths,
                                        "--at", "29", "--window", "10"])
        self.assertEqual(code, 0)
        self.assertIn("60 agents, 30 steps", out.getvalue())
        self.assertEqual(out.getvalue().count("% of agent-steps"), 3)

    def test_bad_input_is_refused_naming_it(self):
        with tempfile.TemporaryDirectory() as tmp:
            cases = [
                (MAP, PATHS.replace("1: ", "7: "), [], "expected 'agent: (x,y),...' for agent 1"),
                (MAP, PATHS.replace("(4,2),(4,2),(4,2),(4,2)", "(4,2),(9,2),(4,2),(4,2)"), [], "outside the 5 x 3 map"),
                (MAP, PATHS.replace("(3,0),", ""), [], "paths of different lengths"),
                (MAP, PATHS, ["--at", "3"], "--at 3: the paths cover steps 0..2"),
                ("height 3\n", PATHS, [], "not a MovingAI map header"),
            ]
            for map_text, paths_text, args, message in cases:
                code, _, err = run(tmp, map_text, paths_text, *args)
                self.assertEqual(code, 2, message)
                self.assertIn(message, err)


if __name__ == "__main__":
    unittest.main()
