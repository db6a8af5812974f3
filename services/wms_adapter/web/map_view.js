// The site map on one canvas: walls and shelves drawn once into an offscreen canvas, then every
// frame the layers and robots over it (no DOM node per robot). Robots are discs with a heading
// line, coloured by state; paused ones carry two bars, lost ones (not heard of while others are)
// are hollow. Layers, each of which the page can switch off: the risk map's iso-levels, the
// roadmap (faint, drawn once into a canvas of its own), each robot's route (its released base
// solid, the planned horizon dashed, in the robot's own colour, which also rings the robot) and
// the station queues (how many wait), and the people the robots see (pink diamonds with a line
// along their velocity when it is known: what the robots' sensors report, not a simulator's truth).

import { isStale, newestUpdate } from './fleet_model.js';

export const MODE_COLOURS = {
  idle: '#8a93a6',
  moving: '#1f9d55',
  waiting: '#e0a100',
  loading: '#2f6fde',
  charging: '#7a3fd1',
  blocked: '#e8590c',
  fault: '#d0021b',
};

/** The layers the page can switch on and off (all on by default). */
export const LAYERS = {
  risk: 'risk map',
  roadmap: 'roadmap',
  routes: 'routes (released solid, planned dashed)',
  queues: 'station queues',
  people: 'people seen',
};

export const PERSON_COLOUR = '#d6336c';

/** A colour of the robot's own, the same on every page and visit (from its id). */
export function robotColour(id) {
  let h = 2166136261;
  for (let i = 0; i < id.length; i++) {
    h = Math.imul(h ^ id.charCodeAt(i), 16777619);
  }
  // Golden-angle steps spread neighbouring hashes around the wheel; a few lightness levels more.
  const hue = Math.round(((h >>> 0) % 360) * 137.508) % 360;
  const light = [42, 34, 50][(h >>> 9) % 3];
  return `hsl(${hue}, 75%, ${light}%)`;
}

export class MapView {
  constructor(canvas) {
    this.canvas = canvas;
    this.ctx = canvas.getContext('2d');
    this.site = null;
    this.background = null;
    this.selected = '';
    this.riskLayer = null; // the risk map's iso-levels as an image, one pixel per cell
    this.riskOf = null;
    this.roadmapLayer = null; // the roadmap drawn at the current size
    this.roadmapOf = null;
    this.layers = Object.fromEntries(Object.keys(LAYERS).map((k) => [k, true]));
    this.frameTimes = new Float64Array(4096); // rAF timestamps, a ring (for the frame-rate figure)
    this.frames = 0;
    new ResizeObserver(() => this.resize()).observe(canvas);
    this.resize();
  }

  setSite(site) {
    this.site = site;
    this.bounds = siteBounds(site);
    this.background = null;
    this.roadmapLayer = null;
    this.resize();
  }

  resize() {
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(this.canvas.clientWidth * dpr));
    const h = Math.max(1, Math.round(this.canvas.clientHeight * dpr));
    if (this.canvas.width !== w || this.canvas.height !== h) {
      this.canvas.width = w;
      this.canvas.height = h;
      this.background = null;
      this.roadmapLayer = null;
    }
    const b = this.bounds || { x0: 0, y0: 0, x1: 10, y1: 10 };
    const pad = 12 * dpr;
    this.scale = Math.min((w - 2 * pad) / (b.x1 - b.x0), (h - 2 * pad) / (b.y1 - b.y0));
    this.offX = (w - this.scale * (b.x1 - b.x0)) / 2 - this.scale * b.x0;
    this.offY = (h - this.scale * (b.y1 - b.y0)) / 2 - this.scale * b.y0;
    this.dpr = dpr;
  }

  /** Map frame (m, y up) to canvas pixels (y down). */
  toCanvas(x, y) {
    return [this.offX + x * this.scale, this.canvas.height - (this.offY + y * this.scale)];
  }

  toWorld(px, py) {
    return [(px - this.offX) / this.scale, (this.canvas.height - py - this.offY) / this.scale];
  }

  /** The robot under a click (canvas CSS pixels), or ''. */
  robotAt(model, cssX, cssY) {
    const [x, y] = this.toWorld(cssX * this.dpr, cssY * this.dpr);
    let best = '';
    let bestD = Infinity;
    for (const r of model.robots.values()) {
      const d = Math.hypot(r.pose.x - x, r.pose.y - y);
      if (d < Math.max(0.6, (r.radius || 0.3) * 1.5) && d < bestD) {
        best = r.id;
        bestD = d;
      }
    }
    return best;
  }

  drawBackground() {
    const bg = document.createElement('canvas');
    bg.width = this.canvas.width;
    bg.height = this.canvas.height;
    const g = bg.getContext('2d');
    g.fillStyle = '#ffffff';
    g.fillRect(0, 0, bg.width, bg.height);
    const map = this.site && this.site.map;
    if (map) {
      g.fillStyle = '#3b4150';
      const res = map.resolution;
      const [ox, oy] = map.origin;
      // Runs of blocked cells per row: one rectangle each.
      map.rows.forEach((row, i) => {
        const cy = map.height - 1 - i;
        let start = -1;
        for (let x = 0; x <= row.length; x++) {
          const blocked = x < row.length && row[x] === '#';
          if (blocked && start < 0) {
            start = x;
          } else if (!blocked && start >= 0) {
            const [px, py] = this.toCanvas(ox + start * res, oy + (cy + 1) * res);
            g.fillRect(px, py, (x - start) * res * this.scale + 0.5, res * this.scale + 0.5);
            start = -1;
          }
        }
      });
    }
    if (this.site) {
      const kindColour = { pickup: '#2f6fde', dropoff: '#1f9d55', charging: '#7a3fd1', parking: '#b7bcc8' };
      g.font = `${11 * this.dpr}px system-ui, sans-serif`;
      for (const s of this.site.stations || []) {
        const [px, py] = this.toCanvas(s.x, s.y);
        const size = Math.max(4 * this.dpr, 0.4 * this.scale);
        g.fillStyle = kindColour[s.kinds[0]] || '#999';
        g.globalAlpha = 0.35;
        g.fillRect(px - size / 2, py - size / 2, size, size);
        g.globalAlpha = 1;
        if (s.kinds[0] !== 'parking' && this.scale > 8 * this.dpr) {
          g.fillStyle = '#1d2330';
          g.fillText(s.name, px + size / 2 + 2, py - size / 2);
        }
      }
    }
    this.background = bg;
  }

  draw(model, now) {
    this.frameTimes[this.frames % this.frameTimes.length] = now;
    this.frames++;
    if (!this.background) {
      this.drawBackground();
    }
    const g = this.ctx;
    g.drawImage(this.background, 0, 0);
    if (model.risk && this.layers.risk) {
      this.drawRisk(model.risk);
    }
    const roadmap = model.roadmap && !model.roadmap.too_large ? model.roadmap : null;
    if (roadmap && this.layers.roadmap) {
      this.drawRoadmap(roadmap);
    }
    const routes = this.layers.routes && model.releases && model.releases.size > 0;
    if (routes) {
      this.drawReleases(model.releases);
    }
    if (roadmap && this.layers.queues && model.queues) {
      this.drawQueues(roadmap, model.queues);
    }
    if (this.layers.people && model.people && model.people.length) {
      this.drawPeople(model.people);
    }
    const newest = newestUpdate(model.robots);
    const labels = this.scale > 14 * this.dpr;
    g.font = `${10 * this.dpr}px system-ui, sans-serif`;
    g.lineWidth = 1.5 * this.dpr;
    for (const r of model.robots.values()) {
      const [px, py] = this.toCanvas(r.pose.x, r.pose.y);
      const rad = Math.max(3 * this.dpr, (r.radius || 0.3) * this.scale);
      const colour = r.fault ? MODE_COLOURS.fault : MODE_COLOURS[r.mode] || '#555';
      const stale = isStale(r, newest);
      g.beginPath();
      g.arc(px, py, rad, 0, 2 * Math.PI);
      if (stale) {
        g.setLineDash([3 * this.dpr, 3 * this.dpr]);
        g.strokeStyle = '#555';
        g.stroke();
        g.setLineDash([]);
      } else {
        g.fillStyle = colour;
        g.fill();
      }
      g.beginPath();
      g.moveTo(px, py);
      g.lineTo(px + Math.cos(r.pose.theta) * rad * 1.6, py - Math.sin(r.pose.theta) * rad * 1.6);
      g.strokeStyle = '#1d2330';
      g.stroke();
      if (r.paused) {
        g.fillStyle = '#fff';
        g.fillRect(px - rad * 0.45, py - rad * 0.5, rad * 0.3, rad);
        g.fillRect(px + rad * 0.15, py - rad * 0.5, rad * 0.3, rad);
      }
      if (routes && model.releases.has(r.id)) {
        g.beginPath();
        g.arc(px, py, rad + 1.5 * this.dpr, 0, 2 * Math.PI);
        g.strokeStyle = robotColour(r.id);
        g.lineWidth = 2.5 * this.dpr;
        g.stroke();
        g.lineWidth = 1.5 * this.dpr;
      }
      if (r.id === this.selected) {
        g.beginPath();
        g.arc(px, py, rad + 4 * this.dpr, 0, 2 * Math.PI);
        g.strokeStyle = '#2459c6';
        g.lineWidth = 2.5 * this.dpr;
        g.stroke();
        g.lineWidth = 1.5 * this.dpr;
      }
      if (labels) {
        g.fillStyle = '#1d2330';
        g.fillText(r.id, px + rad + 2, py + rad + 8 * this.dpr);
      }
    }
  }

  /** The roadmap, faint: lanes grey, one-way lanes blue, queue lines purple, closed lanes red. */
  drawRoadmap(m) {
    if (this.roadmapOf !== m || !this.roadmapLayer) {
      this.roadmapOf = m;
      const c = document.createElement('canvas');
      c.width = this.canvas.width;
      c.height = this.canvas.height;
      const g = c.getContext('2d');
      const at = (v) => this.toCanvas(m.nodes[2 * v], m.nodes[2 * v + 1]);
      const QUEUE = 3;
      const stroke = (pairs, colour, width, dash, keep = () => true) => {
        g.beginPath();
        for (let i = 0; i + 1 < pairs.length; i += 2) {
          if (!keep(pairs[i], pairs[i + 1])) {
            continue;
          }
          const [x0, y0] = at(pairs[i]);
          const [x1, y1] = at(pairs[i + 1]);
          g.moveTo(x0, y0);
          g.lineTo(x1, y1);
        }
        g.strokeStyle = colour;
        g.lineWidth = width * this.dpr;
        g.setLineDash(dash.map((d) => d * this.dpr));
        g.stroke();
      };
      const queueLine = (a, b) => m.kinds[a] === QUEUE && m.kinds[b] === QUEUE ||
        m.kinds[a] === QUEUE && m.kinds[b] !== 0;
      g.lineCap = 'round';
      stroke(m.lanes || [], 'rgba(120, 130, 150, 0.22)', 0.8, []);
      stroke(m.one_way || [], 'rgba(47, 111, 222, 0.3)', 0.8, [], (a, b) => !queueLine(a, b));
      stroke(m.one_way || [], 'rgba(155, 48, 208, 0.55)', 2.5, [], queueLine);
      stroke(m.closed_lanes || [], 'rgba(208, 2, 27, 0.45)', 1, [3, 3]);
      g.setLineDash([]);
      // Queue places as small rings (robots wait on them), closed nodes as red dots.
      const ring = Math.max(2, 0.12 * this.scale);
      g.strokeStyle = 'rgba(155, 48, 208, 0.7)';
      g.lineWidth = 1.2 * this.dpr;
      for (let v = 0; v < m.kinds.length; v++) {
        if (m.kinds[v] === QUEUE) {
          const [x, y] = at(v);
          g.beginPath();
          g.arc(x, y, ring, 0, 2 * Math.PI);
          g.stroke();
        }
      }
      g.fillStyle = 'rgba(208, 2, 27, 0.6)';
      for (const v of m.closed || []) {
        const [x, y] = at(v);
        g.fillRect(x - ring / 2, y - ring / 2, ring, ring);
      }
      this.roadmapLayer = c;
    }
    this.ctx.drawImage(this.roadmapLayer, 0, 0);
  }

  /** Each robot's release in its own colour: the base (may drive) solid, the horizon dashed. */
  drawReleases(releases) {
    const g = this.ctx;
    const line = (xy, from) => {
      g.beginPath();
      if (from) {
        g.moveTo(...this.toCanvas(from[0], from[1]));
      }
      for (let i = 0; i + 1 < xy.length; i += 2) {
        const [x, y] = this.toCanvas(xy[i], xy[i + 1]);
        if (i === 0 && !from) {
          g.moveTo(x, y);
        } else {
          g.lineTo(x, y);
        }
      }
      g.stroke();
    };
    g.lineCap = 'round';
    g.lineJoin = 'round';
    const width = Math.max(2 * this.dpr, 0.12 * this.scale);
    for (const r of releases.values()) {
      const base = r.base_xy || [];
      const horizon = r.horizon_xy || [];
      g.strokeStyle = robotColour(r.robot);
      if (horizon.length >= 2) {
        g.globalAlpha = 0.75;
        g.lineWidth = Math.max(1.2 * this.dpr, width * 0.45);
        g.setLineDash([5 * this.dpr, 4 * this.dpr]);
        line(horizon, base.length >= 2 ? base.slice(-2) : null);
        g.setLineDash([]);
      }
      if (base.length >= 4) {
        g.globalAlpha = 0.8;
        g.lineWidth = width;
        line(base, null);
      }
      if (base.length >= 2 && r.ends_at_goal) {
        // The base ends at the robot's goal: a small bar across its end.
        const [x, y] = this.toCanvas(base[base.length - 2], base[base.length - 1]);
        g.globalAlpha = 0.9;
        g.fillStyle = g.strokeStyle;
        g.fillRect(x - width, y - width, 2 * width, 2 * width);
      }
    }
    g.globalAlpha = 1;
    g.lineCap = 'butt';
    g.lineJoin = 'miter';
  }

  /** People seen: a diamond of the person's size, a line to where they walk in the next second. */
  drawPeople(people) {
    const g = this.ctx;
    g.fillStyle = PERSON_COLOUR;
    g.strokeStyle = PERSON_COLOUR;
    g.lineWidth = 1.5 * this.dpr;
    g.globalAlpha = 0.85;
    for (const p of people) {
      const [x, y] = this.toCanvas(p.x, p.y);
      const s = Math.max(3.5 * this.dpr, (p.radius || 0.25) * this.scale);
      g.beginPath();
      g.moveTo(x, y - s);
      g.lineTo(x + s, y);
      g.lineTo(x, y + s);
      g.lineTo(x - s, y);
      g.closePath();
      g.fill();
      if (p.velocity_known && (p.vx || p.vy)) {
        g.beginPath();
        g.moveTo(x, y);
        g.lineTo(x + p.vx * this.scale, y - p.vy * this.scale);
        g.stroke();
      }
    }
    g.globalAlpha = 1;
  }

  /** A purple count beside each station with robots waiting in its queue. */
  drawQueues(roadmap, queues) {
    const g = this.ctx;
    const docks = new Map((roadmap.queues || []).map((q) => [q.station, q]));
    g.font = `bold ${10 * this.dpr}px system-ui, sans-serif`;
    g.textBaseline = 'middle';
    for (const q of queues) {
      const shape = docks.get(q.station);
      if (!shape || !q.waiting || !q.waiting.length) {
        continue;
      }
      // At the tail end of the queue, where a robot joining it would look.
      const v = shape.nodes[shape.nodes.length - 1];
      const [x, y] = this.toCanvas(roadmap.nodes[2 * v], roadmap.nodes[2 * v + 1]);
      const text = `${q.waiting.length} waiting`;
      const w = g.measureText(text).width + 8 * this.dpr;
      const h = 14 * this.dpr;
      const bx = x + 8 * this.dpr;
      const by = y - h / 2;
      g.fillStyle = 'rgba(155, 48, 208, 0.9)';
      g.fillRect(bx, by, w, h);
      g.fillStyle = '#fff';
      g.fillText(text, bx + 4 * this.dpr, y);
    }
    g.textBaseline = 'alphabetic';
  }

  /** Iso-levels from white (level 1) to red (level K), translucent; level 0 (no risk) is clear. */
  drawRisk(risk) {
    if (this.riskOf !== risk) {
      this.riskOf = risk;
      const c = document.createElement('canvas');
      c.width = risk.width;
      c.height = risk.height;
      const img = c.getContext('2d').createImageData(risk.width, risk.height);
      const k = Math.max(1, risk.levels);
      let cell = 0;
      for (let i = 0; i + 1 < risk.runs.length; i += 2) {
        const level = risk.runs[i];
        const end = Math.min(cell + risk.runs[i + 1], risk.width * risk.height);
        for (; cell < end; cell++) {
          if (level > 0) {
            // Row-major from the origin (y up); the image's rows go down.
            const x = cell % risk.width;
            const y = risk.height - 1 - Math.floor(cell / risk.width);
            const o = 4 * (y * risk.width + x);
            const f = level / k;
            img.data[o] = 255;
            img.data[o + 1] = Math.round(200 * (1 - f));
            img.data[o + 2] = 0;
            img.data[o + 3] = Math.round(60 + 140 * f);
          }
        }
      }
      c.getContext('2d').putImageData(img, 0, 0);
      this.riskLayer = c;
    }
    const [x0, y1] = this.toCanvas(risk.origin[0], risk.origin[1] + risk.height * risk.resolution);
    const g = this.ctx;
    g.imageSmoothingEnabled = false;
    g.drawImage(this.riskLayer, x0, y1, risk.width * risk.resolution * this.scale, risk.height * risk.resolution * this.scale);
    g.imageSmoothingEnabled = true;
  }

  /** Frames per second over the last `windowMs` of frame timestamps. */
  fps(windowMs = 2000) {
    const n = Math.min(this.frames, this.frameTimes.length);
    if (n < 2) {
      return 0;
    }
    const last = this.frameTimes[(this.frames - 1) % this.frameTimes.length];
    let count = 0;
    let first = last;
    for (let i = 1; i < n; i++) {
      const t = this.frameTimes[(this.frames - 1 - i) % this.frameTimes.length];
      if (last - t > windowMs) {
        break;
      }
      first = t;
      count++;
    }
    return count > 0 ? (count * 1000) / (last - first) : 0;
  }
}

function siteBounds(site) {
  if (site && site.map) {
    const m = site.map;
    return {
      x0: m.origin[0],
      y0: m.origin[1],
      x1: m.origin[0] + m.width * m.resolution,
      y1: m.origin[1] + m.height * m.resolution,
    };
  }
  const xs = (site && site.stations ? site.stations : []).map((s) => s.x);
  const ys = (site && site.stations ? site.stations : []).map((s) => s.y);
  if (!xs.length) {
    return { x0: 0, y0: 0, x1: 10, y1: 10 };
  }
  return { x0: Math.min(...xs) - 2, y0: Math.min(...ys) - 2, x1: Math.max(...xs) + 2, y1: Math.max(...ys) + 2 };
}
