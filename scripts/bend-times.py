#!/usr/bin/env python3
"""What the agents' bends cost, from a load test's replay (docs/algorithms.md, "Bends driven round").

    scripts/bend-times.py RUN_DIR/replay.jsonl.gz [--robot INDEX] [--cruise 0.8] [--reach 0.6]

Walks each robot's path in windows of `reach` metres of travel before and after a point (windows
do not overlap), classes the window by how much the direction of travel turns across it (a 45°
bend: 0.55–1.0 rad, a right-angle corner: 1.3–1.8 rad, straight: < 0.1 rad) and reports the time
the window took beyond its length at cruise: what the bend cost the robot. The median says what a
bend costs when nothing else happens there; the mean also holds stops for other reasons (the end
of a release, a person, a dock). The roadmap's model (Roadmap::bendTime) is what these are checked
against: 45° bends driven round, corners turned on the spot.
"""
import argparse
import bisect
import gzip
import json
import math
import statistics

CLASSES = (("45° bend", 0.55, 1.0), ("corner", 1.3, 1.8), ("straight", 0.0, 0.1))


def wrap(a):
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def windows(track, cruise, reach):
    """(class, seconds lost) for each window of one robot's track [(t, x, y)]."""
    arc = [0.0]
    for k in range(1, len(track)):
        arc.append(arc[-1] + math.hypot(track[k][1] - track[k - 1][1], track[k][2] - track[k - 1][2]))
    k = 0
    while k < len(track):
        a = arc[k]
        before = bisect.bisect_left(arc, a - reach)
        after = bisect.bisect_left(arc, a + reach)
        if before <= 0 or after >= len(track) or arc[after] - arc[before] < 2.0 * reach - 0.05:
            k += 1
            continue
        d1 = math.atan2(track[k][2] - track[before][2], track[k][1] - track[before][1])
        d2 = math.atan2(track[after][2] - track[k][2], track[after][1] - track[k][1])
        turn = abs(wrap(d2 - d1))
        lost = (track[after][0] - track[before][0]) - (arc[after] - arc[before]) / cruise
        for name, lo, hi in CLASSES:
            if lo <= turn < hi:
                yield name, lost
        k = after


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("replay")
    p.add_argument("--robot", type=int, default=None, help="one robot's index (default: every robot)")
    p.add_argument("--cruise", type=float, default=0.8, help="the agents' cruise speed [m/s]")
    p.add_argument("--reach", type=float, default=0.6, help="metres of travel each side of a point")
    args = p.parse_args()
    tracks = {}
    with gzip.open(args.replay, "rt") as f:
        next(f)  # the header: map, dt, people
        for line in f:
            row = json.loads(line)
            for i, r in enumerate(row.get("robots", [])):
                if args.robot is None or i == args.robot:
                    tracks.setdefault(i, []).append((row["t"], r[0], r[1]))
    lost = {name: [] for name, _, _ in CLASSES}
    for track in tracks.values():
        for name, s in windows(track, args.cruise, args.reach):
            lost[name].append(s)
    print(f"{len(tracks)} robot(s), windows of {2 * args.reach:.1f} m of travel, cruise {args.cruise} m/s")
    for name, values in lost.items():
        if values:
            print(f"  {name:9s} {len(values):6d} windows: time beyond cruise median {statistics.median(values):.2f} s, "
                  f"mean {statistics.mean(values):.2f} s")


if __name__ == "__main__":
    main()
