"""scripts/report_ledger.py: the fleet bound, robot-time and station blocks of a run's report."""
import importlib.util
import os
import re
import sys
import unittest

ROOT = sys.argv.pop(1)
spec = importlib.util.spec_from_file_location("report_ledger", os.path.join(ROOT, "scripts", "report_ledger.py"))
rl = importlib.util.module_from_spec(spec)
spec.loader.exec_module(rl)

CATS = ["no_task", "driving", "turning_docking", "dwelling", "waiting_on_robot", "held_by_person",
        "held_by_safety", "charging", "faulted"]


def station(name, series, every=5.0):
    return {"name": name, "visits": 4, "utilisation": 0.25, "queue_mean": sum(series) / len(series) if series else 0.0,
            "queue_max": max(series) if series else 0, "queue_every_s": every, "queue_series": series,
            "cycles": 3, "cycle_p50_s": 9.5, "cycle_p90_s": 12.0, "occupancy_p50_s": 4.0, "occupancy_p90_s": 5.0}


class RobotTime(unittest.TestCase):
    def test_each_robots_bar_fills_the_width_its_shares_say(self):
        rt = {"categories": CATS, "fleet": {"driving": 0.6, "no_task": 0.4},
              "per_robot": {"r1": {"share": {"driving": 0.75, "no_task": 0.25}},
                            "r2": {"share": {"dwelling": 1.0}}}}
        out = rl.robot_time_html(rt, w=640)
        usable = 640 - 70 - 10
        for robot in ("r1", "r2"):
            widths = [float(w) for w in re.findall(r'width="([\d.]+)"[^>]*><title>' + robot + ':', out)]
            self.assertAlmostEqual(sum(widths), usable, delta=0.5, msg=robot)
        self.assertIn("driving <b>60 %</b>", out)

    def test_an_error_is_shown_not_drawn(self):
        self.assertIn("not computed: no replay", rl.robot_time_html({"error": "no replay"}))


class Stations(unittest.TestCase):
    def test_the_queue_over_the_run_is_a_step_line_on_one_scale_for_all_stations(self):
        out = rl.stations_html([station("P-1", [0, 1, 3, 2]), station("D-1", [0, 0, 1, 0])])
        self.assertIn("queue over the run (0–3)", out)
        lines = re.findall(r'points="([^"]+)"', out)
        self.assertEqual(len(lines), 2)
        # Each sample two points (its start and end); y = h - 1 - (h - 2) q / top with h = 22.
        p1 = [tuple(map(float, p.split(","))) for p in lines[0].split()]
        self.assertEqual(len(p1), 8)
        self.assertAlmostEqual(p1[0][1], 21.0)  # q 0: the bottom
        self.assertAlmostEqual(p1[4][1], 1.0)   # q 3 = top: the top
        self.assertAlmostEqual(p1[-1][0], 160.0)  # the last sample ends at the right edge
        d1 = [tuple(map(float, p.split(","))) for p in lines[1].split()]
        self.assertAlmostEqual(d1[4][1], 21.0 - 20.0 / 3.0, places=1)  # q 1 of 3
        self.assertIn("max 3", out)

    def test_a_station_without_samples_gets_a_dash(self):
        out = rl.stations_html([station("P-1", [])])
        self.assertNotIn("<polyline", out)
        self.assertIn("<td>–</td>", out)


if __name__ == "__main__":
    unittest.main()
