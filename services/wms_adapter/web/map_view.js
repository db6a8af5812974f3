// The site map on one canvas: walls and shelves drawn once into an offscreen canvas, then every
// frame the stations and robots over it (no DOM node per robot). Robots are discs with a heading
// line, coloured by state; paused ones carry two bars, lost ones are hollow.

import { STALE_MS } from './fleet_model.js';

export const MODE_COLOURS = {
  idle: '#8a93a6',
  moving: '#1f9d55',
  waiting: '#e0a100',
  loading: '#2f6fde',
  charging: '#7a3fd1',
  blocked: '#e8590c',
  fault: '#d0021b',
};

export class MapView {
  constructor(canvas) {
    this.canvas = canvas;
    this.ctx = canvas.getContext('2d');
    this.site = null;
    this.background = null;
    this.selected = '';
    this.riskLayer = null; // the risk map's iso-levels as an image, one pixel per cell
    this.riskOf = null;
    this.frameTimes = new Float64Array(4096); // rAF timestamps, a ring (for the frame-rate figure)
    this.frames = 0;
    new ResizeObserver(() => this.resize()).observe(canvas);
    this.resize();
  }

  setSite(site) {
    this.site = site;
    this.bounds = siteBounds(site);
    this.background = null;
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
    if (model.risk) {
      this.drawRisk(model.risk);
    }
    const wall = Date.now();
    const labels = this.scale > 14 * this.dpr;
    g.font = `${10 * this.dpr}px system-ui, sans-serif`;
    g.lineWidth = 1.5 * this.dpr;
    for (const r of model.robots.values()) {
      const [px, py] = this.toCanvas(r.pose.x, r.pose.y);
      const rad = Math.max(3 * this.dpr, (r.radius || 0.3) * this.scale);
      const colour = r.fault ? MODE_COLOURS.fault : MODE_COLOURS[r.mode] || '#555';
      const stale = wall - r.receivedAt > STALE_MS;
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
