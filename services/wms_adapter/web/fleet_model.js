// What the page knows of the fleet, fed by the stream: robots (with when each was last heard of and
// the people each sees), tasks, recent events, the traffic layer (roadmap, releases, station
// queues), contacts and near misses (counted by the adapter), and the live figures.

const TERMINAL = new Set(['done', 'failed', 'cancelled', 'rejected']);
export const STALE_MS = 5000; // a robot not heard of for this long is drawn as lost

/**
 * Whether robot `r` counts as lost: not heard of for STALE_MS while others were (`newest`: when
 * the latest robot update arrived). When the whole fleet is quiet — a run that ended, a paused
 * simulation — robots stay where they were last seen and the figures say how long ago that was.
 */
export function isStale(r, newest) {
  return newest - r.receivedAt > STALE_MS;
}

/** When the latest robot update arrived (0: none). */
export function newestUpdate(robots) {
  let newest = 0;
  for (const r of robots.values()) {
    newest = Math.max(newest, r.receivedAt || 0);
  }
  return newest;
}

export class FleetModel {
  constructor() {
    this.robots = new Map(); // id -> robot JSON + receivedAt
    this.tasks = new Map(); // id -> {id, state, robot, reason, stamp_ns, queuedNs, assignedNs}
    this.events = []; // newest last, at most 200
    this.doneStamps = []; // stamp_ns of done events
    this.latencies = []; // queued -> assigned, s
    this.latestStampNs = 0;
    this.firstStampNs = 0;
    this.managerOnline = true;
    this.risk = null; // the risk map's latest iso-level grid (GET /v1/stream `risk`)
    this.roadmap = null; // the traffic manager's roadmap (`roadmap`); null: none (reactive traffic)
    this.releases = new Map(); // robot -> its release (`releases`): base and horizon
    this.queues = []; // per station queue: {station, at, waiting: [robot, ...], length}
    this.proximity = null; // contacts and near misses (`proximity`), as /v1/metrics has them
    this.version = 0; // grows with every change, so views redraw only when needed
  }

  snapshot(data, now) {
    this.robots.clear();
    // The traffic layer follows the snapshot in the same stream (when there is one to send).
    this.roadmap = null;
    this.releases.clear();
    this.queues = [];
    this.robotsUpdate(data.robots || [], now);
    for (const t of data.tasks || []) {
      const old = this.tasks.get(t.id) || {};
      this.tasks.set(t.id, { ...old, ...t });
      this.stamp(t.stamp_ns);
    }
    this.managerOnline = data.fleet_manager !== 'unreachable';
    this.version++;
  }

  setRisk(risk) {
    this.risk = risk;
    this.version++;
  }

  setRoadmap(roadmap) {
    this.roadmap = roadmap;
    this.version++;
  }

  /** A `releases` message: the whole set when `all`, else the releases that changed. */
  releasesUpdate(data) {
    if (data.all) {
      this.releases.clear();
    }
    for (const r of data.releases || []) {
      this.releases.set(r.robot, r);
    }
    for (const id of data.removed || []) {
      this.releases.delete(id);
    }
    this.version++;
  }

  setProximity(data) {
    this.proximity = data;
    this.version++;
  }

  /** The people the live robots see: [{x, y, vx, vy, radius, velocity_known, robot}]. */
  peopleSeen() {
    const out = [];
    const newest = newestUpdate(this.robots);
    for (const r of this.robots.values()) {
      if (isStale(r, newest)) {
        continue; // its list is as old as the robot's news
      }
      for (const p of r.people_seen || []) {
        out.push({ ...p, robot: r.id });
      }
    }
    return out;
  }

  setQueues(data) {
    this.queues = data.queues || [];
    this.version++;
  }

  robotsUpdate(robots, now) {
    for (const r of robots) {
      r.receivedAt = now;
      this.robots.set(r.id, r);
    }
    this.version++;
  }

  task(e) {
    const t = this.tasks.get(e.id) || { id: e.id };
    if (e.state === 'queued' || e.state === 'requeued') {
      t.queuedNs = e.stamp_ns;
    } else if (e.state === 'assigned' && t.queuedNs !== undefined) {
      this.latencies.push((e.stamp_ns - t.queuedNs) / 1e9);
      if (this.latencies.length > 200) {
        this.latencies.shift();
      }
      t.queuedNs = undefined;
    }
    if (e.state === 'done') {
      this.doneStamps.push(e.stamp_ns);
    }
    Object.assign(t, { state: e.state, robot: e.robot, reason: e.reason, stamp_ns: e.stamp_ns, eta_ns: e.eta_ns || 0 });
    this.tasks.set(e.id, t);
    this.stamp(e.stamp_ns);
    this.log(`${e.id}: ${e.state}${e.robot ? ' (' + e.robot + ')' : ''}${e.reason ? ' — ' + e.reason : ''}`);
    // Finished tasks stay listed for a while, but the map of tasks does not grow for ever.
    if (this.tasks.size > 2000) {
      for (const [id, old] of this.tasks) {
        if (TERMINAL.has(old.state)) {
          this.tasks.delete(id);
          if (this.tasks.size <= 1500) {
            break;
          }
        }
      }
    }
    this.version++;
  }

  log(text) {
    this.events.push({ at: new Date(), text });
    if (this.events.length > 200) {
      this.events.shift();
    }
    this.version++;
  }

  stamp(ns) {
    if (!ns) {
      return;
    }
    this.latestStampNs = Math.max(this.latestStampNs, ns);
    if (!this.firstStampNs || ns < this.firstStampNs) {
      this.firstStampNs = ns;
    }
  }

  openTasks() {
    return [...this.tasks.values()].filter((t) => !TERMINAL.has(t.state));
  }

  /** Figures for the panel: name -> text. Times are the fleet's clock (simulated in a simulation). */
  figures(now) {
    const byMode = {};
    let stale = 0;
    const newest = newestUpdate(this.robots);
    for (const r of this.robots.values()) {
      if (isStale(r, newest)) {
        stale++;
        continue;
      }
      const k = r.fault ? 'fault' : r.paused ? 'paused' : r.mode;
      byMode[k] = (byMode[k] || 0) + 1;
    }
    const hourNs = 3600e9;
    const since = this.latestStampNs - hourNs;
    const doneHour = this.doneStamps.filter((s) => s >= since).length;
    const spanS = Math.min(3600, (this.latestStampNs - this.firstStampNs) / 1e9);
    const sorted = [...this.latencies].sort((a, b) => a - b);
    const median = sorted.length ? sorted[Math.floor(sorted.length / 2)] : null;
    const open = this.openTasks();
    const px = this.proximity;
    const clearance = (v) => (v === null || v === undefined ? '—' : `${v.toFixed(2)} m`);
    const seen = this.peopleSeen();
    const seers = new Set(seen.map((p) => p.robot)).size;
    return {
      robots: `${this.robots.size - stale} live` + (stale ? `, ${stale} not heard of` : '') +
        (newest && now - newest > STALE_MS ? ` — no update for ${Math.round((now - newest) / 1000)} s` : ''),
      'by state': Object.entries(byMode).map(([k, n]) => `${k} ${n}`).join(', ') || '—',
      'tasks open': `${open.length} (${open.filter((t) => t.state === 'queued' || t.state === 'requeued').length} waiting)`,
      'tasks done': String(this.doneStamps.length),
      'done per hour': spanS > 30 ? (doneHour * 3600 / spanS).toFixed(1) : '—',
      'assignment latency': median === null ? '—' : `median ${median.toFixed(2)} s (${sorted.length} tasks)`,
      // Sightings, not people: two robots that see one person both report it (no identities).
      'people seen': seen.length ? `${seen.length} sightings by ${seers} robot${seers === 1 ? '' : 's'}` : 'none',
      contacts: px ? `${px.robot_robot.contacts} robot–robot, ${px.robot_person.contacts} robot–person` : '—',
      'near misses': px
        ? `${px.robot_robot.near_misses} robot–robot, ${px.robot_person.near_misses} robot–person (< ${px.near_miss_margin_m} m)`
        : '—',
      closest: px ? `${clearance(px.robot_robot.min_clearance_m)} robot–robot, ${clearance(px.robot_person.min_clearance_m)} robot–person` : '—',
      'fleet manager': this.managerOnline ? 'online' : 'unreachable',
    };
  }
}
