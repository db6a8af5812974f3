// Frame rate of the dashboard page under a 500-robot feed (a benchmark, not a test).
//
//   node tests/bench/dashboard/replay_fps.mjs REPLAY.jsonl.gz [--robots 500] [--hz 2] [--seconds 20]
//
// REPLAY is a simulator recording (fleet-sim --replay, e.g. reports/<run>/replay.jsonl.gz from
// scripts/demo). Its robots' recorded motion is tiled over copies of its site until there are
// --robots robots (20 robots: 25 copies in a 5 x 5 grid), and replayed in real time at --hz as the
// adapter's /v1/stream sends it (one `event: robots` with every robot's JSON each period) by a small
// server here that also serves the page's files (services/wms_adapter/web) and a site picture of the
// tiled map. Headless Debian chromium (puppeteer-core) loads the page; the frame rate is taken from
// The page's own frame timestamps (requestAnimationFrame, MapView.frameTimes) over --seconds after a
// 3 s warm-up. Prints one JSON line.

import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import zlib from 'node:zlib';
import { createRequire } from 'node:module';
import { fileURLToPath } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const root = path.resolve(here, '../../..');
const require = createRequire(path.join(root, 'tests/browser/package.json'));
const puppeteer = require('puppeteer-core');

const args = process.argv.slice(2);
const opt = (name, dflt) => {
  const i = args.indexOf('--' + name);
  return i >= 0 ? Number(args[i + 1]) : dflt;
};
const replayPath = args.find((a, i) => !a.startsWith('--') && (i === 0 || !args[i - 1].startsWith('--')));
if (!replayPath) {
  console.error('usage: replay_fps.mjs REPLAY.jsonl.gz [--robots N] [--hz F] [--seconds S]');
  process.exit(2);
}
const robotsWanted = opt('robots', 500);
const hz = opt('hz', 2);
const seconds = opt('seconds', 20);

const lines = zlib.gunzipSync(fs.readFileSync(replayPath)).toString('utf8').trim().split('\n');
const header = JSON.parse(lines[0]);
const steps = lines.slice(1).map((l) => JSON.parse(l)).filter((s) => s.robots);
const perSite = header.robots.length;
const copies = Math.ceil(robotsWanted / perSite);
const cols = Math.ceil(Math.sqrt(copies));
const rowsOfCopies = Math.ceil(copies / cols);
const m = header.map;
const w = m.width * m.resolution;
const h = m.height * m.resolution;

// The tiled site: copy (i, j) of the map at (i * w, j * h).
const tileRows = m.rows.map((r) => r.replace(/[^.]/g, '#'));
const rows = [];
for (let j = rowsOfCopies - 1; j >= 0; j--) {
  for (const r of tileRows) {
    rows.push(r.repeat(cols));
  }
}
const stations = [];
for (let k = 0; k < copies; k++) {
  const ox = (k % cols) * w;
  const oy = Math.floor(k / cols) * h;
  for (const s of header.stations || []) {
    const [x, y, theta] = s.pose;
    stations.push({ name: `${s.name}#${k}`, x: x + ox, y: y + oy, theta, kinds: [s.kind] });
  }
}
const site = {
  name: `${header.scenario} x${copies}`,
  map: { width: m.width * cols, height: m.height * rowsOfCopies, resolution: m.resolution, origin: m.origin, rows },
  stations,
  homes: {},
};

const modes = ['idle', 'moving', 'waiting', 'loading', 'charging', 'blocked', 'fault'];
function robotsAt(stepIndex, stampNs) {
  const s = steps[stepIndex % steps.length];
  const out = [];
  for (let k = 0; k < copies && out.length < robotsWanted; k++) {
    const ox = (k % cols) * w;
    const oy = Math.floor(k / cols) * h;
    header.robots.forEach((r, i) => {
      if (out.length >= robotsWanted) {
        return;
      }
      const [x, y, theta, v, battery, , mode, task] = s.robots[i];
      out.push({
        id: `${r.id}-${k}`,
        pose: { x: x + ox, y: y + oy, theta },
        heading_deg: (theta * 180) / Math.PI,
        v,
        w: 0,
        mode: modes.includes(mode) ? mode : v > 0.01 ? 'moving' : 'idle',
        fault: false,
        paused: false,
        battery,
        task: task || '',
        radius: r.radius,
        position_sigma: 0.01,
        stamp_ns: stampNs,
      });
    });
  }
  return out;
}

const web = path.join(root, 'services/wms_adapter/web');
const types = { '.html': 'text/html', '.js': 'text/javascript', '.css': 'text/css' };
const server = http.createServer((req, res) => {
  const url = new URL(req.url, 'http://x');
  if (url.pathname === '/v1/session') {
    res.writeHead(200, { 'Content-Type': 'application/json' });
    res.end(JSON.stringify({ auth: 'off', csrf: '' }));
  } else if (url.pathname === '/v1/site') {
    res.writeHead(200, { 'Content-Type': 'application/json' });
    res.end(JSON.stringify(site));
  } else if (url.pathname === '/v1/stream') {
    res.writeHead(200, { 'Content-Type': 'text/event-stream', 'Cache-Control': 'no-cache' });
    let step = 0;
    const every = Math.max(1, Math.round(1 / hz / header.dt)); // replay in real time
    const send = (event, data) => res.write(`event: ${event}\ndata: ${JSON.stringify(data)}\n\n`);
    send('snapshot', { robots: robotsAt(0, 1), tasks: [], fleet_manager: 'online' });
    const timer = setInterval(() => {
      step += every;
      send('robots', { robots: robotsAt(step, step * header.dt * 1e9), fleet_manager: 'online' });
    }, 1000 / hz);
    req.on('close', () => clearInterval(timer));
  } else {
    const name = url.pathname.replace(/^\/dashboard\/?/, '') || 'index.html';
    const file = path.join(web, path.basename(name));
    if (!fs.existsSync(file)) {
      res.writeHead(404);
      res.end();
      return;
    }
    res.writeHead(200, { 'Content-Type': types[path.extname(file)] || 'application/octet-stream' });
    res.end(fs.readFileSync(file));
  }
});
await new Promise((r) => server.listen(0, '127.0.0.1', r));
const port = server.address().port;

const browser = await puppeteer.launch({
  executablePath: '/usr/bin/chromium',
  headless: true,
  args: ['--no-sandbox', '--disable-dev-shm-usage', '--no-first-run'],
});
try {
  const page = await browser.newPage();
  await page.setViewport({ width: 1400, height: 900 });
  await page.goto(`http://127.0.0.1:${port}/dashboard/`);
  await page.waitForFunction(() => window.fleetDashboard && window.fleetDashboard.ready, { timeout: 20000 });
  await new Promise((r) => setTimeout(r, 3000));
  const from = await page.evaluate(() => performance.now());
  await new Promise((r) => setTimeout(r, seconds * 1000));
  const result = await page.evaluate((t0) => {
    const v = window.fleetDashboard.view;
    const n = Math.min(v.frames, v.frameTimes.length);
    const times = [];
    for (let i = n - 1; i >= 0; i--) {
      const t = v.frameTimes[(v.frames - 1 - i) % v.frameTimes.length];
      if (t >= t0) {
        times.push(t);
      }
    }
    const gaps = times.slice(1).map((t, i) => t - times[i]).sort((a, b) => a - b);
    const q = (p) => (gaps.length ? gaps[Math.min(gaps.length - 1, Math.floor(p * gaps.length))] : NaN);
    // The worst one-second window.
    let worst = Infinity;
    for (let s = times[0]; s + 1000 <= times[times.length - 1]; s += 250) {
      worst = Math.min(worst, times.filter((t) => t >= s && t < s + 1000).length);
    }
    return {
      robots: window.fleetDashboard.model.robots.size,
      frames: times.length,
      span_s: (times[times.length - 1] - times[0]) / 1000,
      fps: (times.length - 1) / ((times[times.length - 1] - times[0]) / 1000),
      worst_1s_window_frames: worst,
      frame_interval_ms: { p50: q(0.5), p99: q(0.99), max: gaps[gaps.length - 1] },
      ring_covers_window: v.frames - n === 0 || times.length < v.frameTimes.length,
    };
  }, from);
  await page.screenshot({ path: path.join(process.env.DASH_SHOTS || '.', 'replay-500.png') });
  console.log(JSON.stringify({ replay: replayPath, feed_hz: hz, seconds, ...result }));
} finally {
  await browser.close();
  server.close();
}
