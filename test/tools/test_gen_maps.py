"""Tests of tools/gen_maps.py's LoRR-like warehouse: the documented layout rule, the checked-in
maps/lorr-warehouse-140-500.map being exactly its output, and the simulator reading it.
Run: GDRHCR_SIM=build/src/gdrhcr_sim python3 -m unittest discover -s test/tools"""
import json
import os
import subprocess
import sys
import tempfile
import unittest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tools"))
import gen_maps  # noqa: E402

SIM = os.environ.get("GDRHCR_SIM", os.path.join(ROOT, "build", "src", "gdrhcr_sim"))
ARGS = (500, 140, 10, 2, 2, 1, 5, 3)


class LorrWarehouseTest(unittest.TestCase):
    def test_layout_follows_the_rule(self):
        rows = gen_maps.lorr_warehouse(*ARGS)
        self.assertEqual(len(rows), 140)
        self.assertTrue(all(len(r) == 500 for r in rows))
        blocked = sum(r.count("@") for r in rows)
        self.assertEqual(blocked, 41 * 45 * 10 * 2)
        self.assertEqual(140 * 500 - blocked, 33100)
        self.assertTrue(gen_maps.connected(rows))
        # The first block: rows 3-4, columns 5-14; the next one starts after a 2-column aisle.
        self.assertEqual("".join(rows[3][5:15]), "@" * 10)
        self.assertEqual("".join(rows[4][15:17]), "..")
        self.assertEqual(rows[4][17], "@")
        # Side zones and top margin are free; workstations E at odd rows of the outer columns.
        self.assertTrue(all(rows[y][x] != "@" for y in range(140) for x in list(range(5)) + list(range(495, 500))))
        self.assertEqual(rows[1][0], "E")
        self.assertEqual(rows[1][499], "E")
        self.assertEqual(rows[2][0], ".")
        # Service points S right above and below every block, nowhere else.
        self.assertEqual(rows[2][5], "S")
        self.assertEqual(rows[5][14], "S")
        self.assertEqual(rows[2][15], ".")
        for y, r in enumerate(rows):
            for x, c in enumerate(r):
                if c == "S":
                    self.assertTrue(any(0 <= yy < 140 and rows[yy][x] == "@" for yy in (y - 1, y + 1)), (x, y))

    def test_sizes_that_do_not_fit_are_rejected(self):
        with self.assertRaises(ValueError):
            gen_maps.lorr_warehouse(501, 140, 10, 2, 2, 1, 5, 3)
        with self.assertRaises(ValueError):
            gen_maps.lorr_warehouse(500, 141, 10, 2, 2, 1, 5, 3)
        with self.assertRaises(ValueError):
            gen_maps.lorr_warehouse(10, 10, 10, 2, 2, 1, 5, 3)

    def test_checked_in_map_is_the_generator_output(self):
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "m.map")
            with open(os.devnull, "w") as null:
                old, sys.stdout = sys.stdout, null
                try:
                    gen_maps.write_map(path, gen_maps.lorr_warehouse(*ARGS), "test")
                finally:
                    sys.stdout = old
            with open(path) as a, open(os.path.join(ROOT, "maps", "lorr-warehouse-140-500.map")) as b:
                self.assertEqual(a.read(), b.read())

    @unittest.skipUnless(os.path.exists(SIM), "gdrhcr_sim not built")
    def test_simulator_runs_on_it(self):
        out = subprocess.run([SIM, "--map", os.path.join(ROOT, "maps", "lorr-warehouse-140-500.map"),
                              "--agents", "200", "--steps", "5", "--quiet"],
                             capture_output=True, text=True, timeout=120)
        self.assertEqual(out.returncode, 0, out.stderr)
        j = json.loads(out.stdout)
        self.assertEqual(j["agents"], 200)
        self.assertEqual(j["collisions"], 0)


if __name__ == "__main__":
    unittest.main()
