#!/usr/bin/env python3
"""Independent check of a plan written by `fleetctl traffic-bench --out plan.json` on a MovingAI map.

Checks, for every step: every agent on a free cell of the map; every move to a 4-neighbour or a wait;
no two agents on one cell (vertex conflict); no two agents swapping cells; with --rotations, no cycle
of agents each moving into the cell the next one leaves. For a lifelong plan it also recounts the
goals reached from the plan and the goal list and compares with the file's `goals_reached`.

Written apart from the C++ planner and its checker (libs/traffic plan_check) on purpose: it shares
no code with either. Prints OK or the first conflicts; exit 0 when valid, 1 on conflicts, 2 on bad
input.

Usage: scripts/check-plan.py MAP.map PLAN.json [--rotations] [--max N]
"""
import argparse
import json
import sys


def read_map(path):
    with open(path, encoding="ascii") as f:
        lines = f.read().split("\n")
    height = width = None
    k = 0
    while k < len(lines):
        words = lines[k].split()
        k += 1
        if not words:
            continue
        if words[0] == "map":
            break
        if words[0] == "height":
            height = int(words[1])
        elif words[0] == "width":
            width = int(words[1])
    if height is None or width is None:
        raise ValueError(f"{path}: no height/width header")
    rows = [r.rstrip("\r") for r in lines[k:k + height]]
    if len(rows) != height or any(len(r) != width for r in rows):
        raise ValueError(f"{path}: grid does not match height {height} x width {width}")
    free = [[ch in ".GS" for ch in r] for r in rows]
    return width, height, free


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("map")
    ap.add_argument("plan")
    ap.add_argument("--rotations", action="store_true", help="also report rotation cycles")
    ap.add_argument("--max", type=int, default=10, help="stop after this many conflicts")
    a = ap.parse_args()
    try:
        width, height, free = read_map(a.map)
        with open(a.plan, encoding="utf-8") as f:
            doc = json.load(f)
        plan = doc["plan"]
    except (OSError, ValueError, KeyError) as e:
        print(f"check-plan: {e}", file=sys.stderr)
        return 2

    found = []

    def report(t, what):
        found.append(f"step {t}: {what}")
        return len(found) >= a.max

    def done():
        for line in found:
            print(line)
        print(f"{len(found)} conflict(s) found (stopped at the first {a.max})" if len(found) >= a.max
              else f"{len(found)} conflict(s)")
        return 1

    n = len(plan[0]) if plan else 0
    prev = None
    for t, config in enumerate(plan):
        if len(config) != n:
            if report(t, f"{len(config)} agents, step 0 has {n}"):
                return done()
            prev = None
            continue
        cells = [tuple(c) for c in config]
        ok = True
        seen = {}
        for i, (x, y) in enumerate(cells):
            if not (0 <= x < width and 0 <= y < height) or not free[y][x]:
                ok = False
                if report(t, f"agent {i} on blocked or outside cell ({x},{y})"):
                    return done()
                continue
            if (x, y) in seen:
                if report(t, f"vertex conflict: agents {seen[(x, y)]} and {i} on ({x},{y})"):
                    return done()
            else:
                seen[(x, y)] = i
        if prev is not None and ok:
            before = {c: i for i, c in enumerate(prev)}
            for i, ((x0, y0), (x1, y1)) in enumerate(zip(prev, cells)):
                if abs(x1 - x0) + abs(y1 - y0) > 1:
                    if report(t, f"agent {i} jumps from ({x0},{y0}) to ({x1},{y1})"):
                        return done()
                j = before.get((x1, y1))
                if j is not None and j > i and (x1, y1) != (x0, y0) and cells[j] == (x0, y0):
                    if report(t, f"swap: agents {i} and {j} between ({x0},{y0}) and ({x1},{y1})"):
                        return done()
            if a.rotations:
                # i follows j when i moves into j's cell and j moves on: each agent follows at most one
                # other, so a cycle is found by walking from each agent with colours.
                follows = {}
                for i in range(n):
                    if cells[i] != prev[i]:
                        j = before.get(cells[i])
                        if j is not None and j != i and cells[j] != prev[j]:
                            follows[i] = j
                colour = {}
                for s in follows:
                    path = []
                    v = s
                    while v in follows and v not in colour:
                        colour[v] = s
                        path.append(v)
                        v = follows[v]
                    if v in colour and colour[v] == s and v in path:
                        cyc = path[path.index(v):]
                        if report(t, f"rotation: agents {' '.join(map(str, cyc))}"):
                            return done()
        prev = cells if ok else None

    if found:
        return done()
    extra = ""
    if doc.get("mode") == "lifelong" and "goals" in doc and "goals_reached" in doc:
        events = {}
        for step, agent, cell in doc["goals"]:
            events.setdefault(step, []).append((agent, None if cell is None else tuple(cell)))
        goal = [None] * n
        reached = 0
        for t in range(len(plan)):
            for agent, cell in events.get(t, []):
                goal[agent] = cell
            if t + 1 < len(plan):
                for i in range(n):
                    if goal[i] is not None and tuple(plan[t + 1][i]) == goal[i]:
                        reached += 1
        if reached != doc["goals_reached"]:
            print(f"goals reached: the plan shows {reached}, the file says {doc['goals_reached']}")
            return 1
        extra = f", {reached} goals reached (matches the file)"
    print(f"OK: {n} agents, {max(len(plan) - 1, 0)} steps, no conflicts"
          f"{' or rotations' if a.rotations else ''}{extra}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
