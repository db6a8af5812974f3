"""scripts/fleet-figures reads task times and requeues from a run's fleet.db as the store writes it."""
import importlib.machinery
import importlib.util
import os
import sqlite3
import sys
import tempfile
import unittest

ROOT = sys.argv.pop(1)
loader = importlib.machinery.SourceFileLoader("fleet_figures", os.path.join(ROOT, "scripts", "fleet-figures"))
spec = importlib.util.spec_from_loader("fleet_figures", loader)
ff = importlib.util.module_from_spec(spec)
loader.exec_module(ff)


def db_with(rows):
    d = tempfile.mkdtemp()
    path = os.path.join(d, "fleet.db")
    db = sqlite3.connect(path)
    db.execute("create table transitions(seq integer primary key autoincrement, task_id text, from_state text,"
               " to_state text, robot text, reason text, stamp_ns integer)")
    for task, frm, to, t in rows:
        db.execute("insert into transitions(task_id, from_state, to_state, stamp_ns) values (?, ?, ?, ?)",
                   (task, frm, to, int(t * 1e9)))
    db.commit()
    return path


class TaskTimes(unittest.TestCase):
    def test_a_requeue_is_counted_and_the_time_runs_from_the_last_assignment(self):
        # The store's own sequence for a task a robot gave up: en_route -> requeued -> assigned.
        path = db_with([("a", None, "queued", 0), ("a", "queued", "assigned", 1), ("a", "assigned", "en_route", 2),
                        ("a", "en_route", "requeued", 50), ("a", "requeued", "assigned", 60),
                        ("a", "assigned", "done", 100),
                        ("b", None, "queued", 0), ("b", "queued", "assigned", 5), ("b", "assigned", "done", 25)])
        times, requeues = ff.task_times(path)
        self.assertEqual(requeues, 1)
        self.assertEqual(sorted(times), [20.0, 40.0])

    def test_a_run_without_requeues_counts_none(self):
        path = db_with([("a", None, "queued", 0), ("a", "queued", "assigned", 1), ("a", "assigned", "done", 11)])
        self.assertEqual(ff.task_times(path), ([10.0], 0))

    def test_done_within_counts_from_the_first_task_posted(self):
        path = db_with([("a", None, "queued", 10), ("a", "queued", "assigned", 11), ("a", "assigned", "done", 600),
                        ("b", None, "queued", 20), ("b", "queued", "assigned", 21), ("b", "assigned", "done", 611)])
        self.assertEqual(ff.done_within(path, 600.0), 1)
        self.assertEqual(ff.done_within(path, 601.0), 2)


if __name__ == "__main__":
    unittest.main()
