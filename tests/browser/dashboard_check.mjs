// Drives the dashboard in Debian's chromium (puppeteer-core: no browser download) against a running
// fleet; run by tests/integration/dashboard/dashboard_browser_test.cpp, which starts the fleet,
// writes the simulator's ground truth to $DASH_DIR/truth.json and restarts the adapter when
// $DASH_DIR/restart.request appears. Exit 0 when every check passed; each check prints one line.
//
// The page is driven through a reverse proxy of our own that serves the adapter under the path
// prefix /fleet/ (as an ingress would): every request the page makes must stay under it.
//
// Env: DASH_URL (the page, served by the adapter itself), DASH_TOKEN (an operator's token: read, submit, operate),
// DASH_VIEWER_TOKEN (a read-only token), DASH_RELEASED (the robot the test released a route to),
// DASH_DIR, DASH_SHOTS (folder for the screenshots).

import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import puppeteer from 'puppeteer-core';

const direct = new URL(process.env.DASH_URL);
const token = process.env.DASH_TOKEN;
const viewerToken = process.env.DASH_VIEWER_TOKEN;
const released = process.env.DASH_RELEASED;
const dir = process.env.DASH_DIR;
const shots = process.env.DASH_SHOTS;
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
let failures = 0;

function check(ok, what) {
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
  if (!ok) {
    failures++;
  }
  return ok;
}

function truth() {
  try {
    return JSON.parse(fs.readFileSync(path.join(dir, 'truth.json'), 'utf8'));
  } catch {
    return null;
  }
}

/** Where robot `id` (the first one when null) is on the screen, in CSS pixels. */
async function robotOnScreen(id) {
  return globalThis.page.evaluate((robotId) => {
    const v = window.fleetDashboard.view;
    const robots = window.fleetDashboard.model.robots;
    const r = robotId ? robots.get(robotId) : robots.values().next().value;
    const [px, py] = v.toCanvas(r.pose.x, r.pose.y);
    const rect = v.canvas.getBoundingClientRect();
    return [rect.left + px / v.dpr, rect.top + py / v.dpr];
  }, id);
}

/** The canvas at the middle of each segment of robot `id`'s released base but the first (the robot
 * stands on it), and whether it is the robot's colour (drawn translucent over the floor). */
async function routePixels(id) {
  return globalThis.page.evaluate((robotId) => {
    const { view: v, model: m } = window.fleetDashboard;
    const probe = document.createElement('canvas').getContext('2d', { willReadFrequently: true });
    probe.fillStyle = '#fff';
    probe.fillRect(0, 0, 1, 1);
    probe.globalAlpha = 0.8;
    probe.fillStyle = window.fleetDashboard.robotColour(robotId);
    probe.fillRect(0, 0, 1, 1);
    const want = [...probe.getImageData(0, 0, 1, 1).data].slice(0, 3);
    const xy = m.releases.get(robotId).base_xy;
    const g = v.canvas.getContext('2d');
    const out = [];
    for (let i = 2; i + 3 < xy.length; i += 2) {
      const [px, py] = v.toCanvas((xy[i] + xy[i + 2]) / 2, (xy[i + 1] + xy[i + 3]) / 2);
      const rgb = [...g.getImageData(Math.round(px), Math.round(py), 1, 1).data].slice(0, 3);
      out.push({ rgb, match: rgb.every((c, k) => Math.abs(c - want[k]) < 45) });
    }
    return out;
  }, id);
}

/** The canvas at the middle of the first 40 lanes of the roadmap away from every robot. */
async function lanePixels() {
  return globalThis.page.evaluate(() => {
    const { view: v, model: m } = window.fleetDashboard;
    const n = m.roadmap.nodes;
    const g = v.canvas.getContext('2d');
    const out = [];
    for (let i = 0; i + 1 < m.roadmap.lanes.length && out.length < 40; i += 2) {
      const [a, b] = [m.roadmap.lanes[i], m.roadmap.lanes[i + 1]];
      const x = (n[2 * a] + n[2 * b]) / 2;
      const y = (n[2 * a + 1] + n[2 * b + 1]) / 2;
      if ([...m.robots.values()].some((r) => Math.hypot(r.pose.x - x, r.pose.y - y) < 1.5)) {
        continue;
      }
      const [px, py] = v.toCanvas(x, y);
      out.push([...g.getImageData(Math.round(px), Math.round(py), 1, 1).data].slice(0, 3));
    }
    return out;
  });
}

async function until(what, fn, ms) {
  const end = Date.now() + ms;
  for (;;) {
    const v = await fn();
    if (v) {
      return v;
    }
    if (Date.now() > end) {
      check(false, `${what} (waited ${ms / 1000} s)`);
      return null;
    }
    await sleep(200);
  }
}

// A reverse proxy on loopback: /fleet/X is the adapter's /X; anything else is counted and refused.
const kPrefix = '/fleet';
const outside = [];
const proxy = http.createServer((req, res) => {
  if (!req.url.startsWith(kPrefix + '/')) {
    outside.push(req.url);
    res.writeHead(404, { 'Content-Type': 'text/plain' });
    res.end('outside the prefix');
    return;
  }
  const up = http.request({ host: direct.hostname, port: direct.port, method: req.method,
                            path: req.url.slice(kPrefix.length), headers: req.headers }, (r) => {
    res.writeHead(r.statusCode, r.headers);
    r.pipe(res);
    // The adapter gone mid-response (the stream of a restarted adapter): the page must see it.
    r.on('close', () => {
      if (!r.complete) {
        res.destroy();
      }
    });
  });
  up.on('error', () => {
    if (res.headersSent) {
      res.destroy();
    } else {
      res.writeHead(502);
      res.end();
    }
  });
  req.pipe(up);
});
await new Promise((resolve) => proxy.listen(0, '127.0.0.1', resolve));
const url = `http://127.0.0.1:${proxy.address().port}${kPrefix}${direct.pathname}`;

// Root in CI: chromium's sandbox needs user namespaces it does not get there.
const browser = await puppeteer.launch({
  executablePath: '/usr/bin/chromium',
  headless: true,
  args: ['--no-sandbox', '--disable-gpu', '--disable-dev-shm-usage', '--no-first-run'],
});
try {
  const page = await browser.newPage();
  globalThis.page = page;
  await page.setViewport({ width: 1400, height: 900 });
  page.on('pageerror', (e) => check(false, `no script error on the page: ${e.message}`));
  const shot = (name) => page.screenshot({ path: path.join(shots, name) });
  const model = (fn, arg) => page.evaluate(fn, arg);

  // The fleet must be up before the page is worth looking at.
  await until('the simulator publishes ground truth', () => truth() && Object.keys(truth().robots).length, 90000);
  await until('the adapter answers', async () => {
    try {
      return (await fetch(url)).ok;
    } catch {
      return false;
    }
  }, 30000);

  // 1. No session: the login prompt, and no data.
  await page.goto(url);
  await page.waitForSelector('#login[open]', { timeout: 10000 });
  check(await model(() => window.fleetDashboard.model.robots.size === 0), 'no robots shown before login');
  await page.type('#login-token', 'not-the-token');
  await page.click('#login-submit');
  await page.waitForFunction(() => document.getElementById('login-error').textContent.includes('wrong token'),
                             { timeout: 10000 });
  check(await page.$('#login[open]') !== null, 'a wrong token keeps the login prompt up');
  check(await model(() => window.fleetDashboard.model.robots.size === 0), 'a wrong token shows no data');
  await shot('1-wrong-token.png');
  check(!(await page.evaluate(() => location.href)).includes('not-the-token'), 'the token is not in the URL');

  // 1b. A read-only token: the data, but no action is offered (the server would refuse it).
  await page.$eval('#login-token', (el) => { el.value = ''; });
  await page.type('#login-token', viewerToken);
  await page.click('#login-submit');
  await page.waitForFunction(() => window.fleetDashboard.ready, { timeout: 15000 });
  await until('a read-only session sees the robots', () => model(() => window.fleetDashboard.model.robots.size > 0), 10000);
  const first = await robotOnScreen(null);
  await page.mouse.click(first[0], first[1]);
  await page.waitForFunction(() => document.getElementById('robot-name').textContent !== '—', { timeout: 5000 });
  await sleep(400);
  const gated = await page.evaluate(() => {
    const submit = document.querySelector('#task-form button[type=submit]');
    const note = document.getElementById('scope-note');
    return {
      robot: [...document.querySelectorAll('[data-robot-action]')].map((b) => [b.disabled, b.title]),
      submit: [submit.disabled, submit.title],
      cancels: document.querySelectorAll('#queue button').length,
      note: note.hidden ? '' : note.textContent,
      who: document.getElementById('who').textContent,
    };
  });
  check(gated.robot.every(([off, why]) => off && why.includes('"operate"')),
        `a read-only session is offered no robot action (${gated.robot.map((b) => b[1]).join('; ')})`);
  check(gated.submit[0] && gated.submit[1].includes('"submit"'), `nor the task form (${gated.submit[1]})`);
  check(gated.cancels === 0, 'nor cancelling tasks');
  check(gated.note.includes('"viewer"') && gated.who.startsWith('viewer'), `and is told why: ${gated.note}`);
  // The robot-time card: the fleet's ledger as a stacked bar whose parts add up to the whole.
  await until('the robot-time bar is drawn', () => page.evaluate(() =>
    document.querySelectorAll('#robot-time-bar span').length > 0), 15000);
  const bar = await page.evaluate(() => ({
    parts: [...document.querySelectorAll('#robot-time-bar span')].map((e) => parseFloat(e.style.width)),
    keys: document.querySelectorAll('#robot-time-keys li').length,
    total: document.getElementById('robot-time-total').textContent,
  }));
  const whole = bar.parts.reduce((a, b) => a + b, 0);
  check(Math.abs(whole - 100) < 0.5 && bar.keys === 9 && /robot/.test(bar.total),
        `the robot-time bar adds up (${whole.toFixed(1)} %, ${bar.keys} categories, ${bar.total})`);
  // And one bar per robot the total names, each with time filed adding up to its whole (a robot
  // just seen is listed before anything is filed for it: its bar is empty).
  // (Read with the total in one go: the card redraws every few seconds and robots may join.)
  const { perRobot, named } = await page.evaluate(() => ({
    perRobot: [...document.querySelectorAll('#robot-time-robots .stacked-bar')].map((b) => ({
      id: b.dataset.robot,
      seconds: parseFloat(b.dataset.seconds),
      whole: [...b.querySelectorAll('span')].reduce((a, e) => a + parseFloat(e.style.width), 0),
    })),
    named: parseInt(document.getElementById('robot-time-total').textContent, 10),
  }));
  check(perRobot.length === named && perRobot.length > 0 &&
        perRobot.some((r) => r.seconds > 0) &&
        perRobot.every((r) => r.id && (r.seconds > 0 ? Math.abs(r.whole - 100) < 0.5 : r.whole === 0)),
        `a bar per robot, each adding up (${perRobot.length} bars for ${named} robots: ` +
        `${perRobot.map((r) => `${r.id} ${r.whole.toFixed(1)} %`).slice(0, 4).join(', ')}${perRobot.length > 4 ? ', ...' : ''})`);
  await shot('1b-read-only.png');
  await page.click('#logout');
  await page.waitForSelector('#login[open]', { timeout: 10000 });

  // 2. The operator's token: the robots, where the simulator has them.
  await page.$eval('#login-token', (el) => { el.value = ''; });
  await page.type('#login-token', token);
  await page.click('#login-submit');
  await page.waitForFunction(() => window.fleetDashboard.ready, { timeout: 15000 });
  check(!(await page.evaluate(() => location.href)).includes(token), 'the token is not in the URL');
  const cookies = await page.cookies();
  const session = cookies.find((c) => c.name === 'fleet_session');
  check(session && session.httpOnly && session.sameSite === 'Strict', 'the session cookie is HttpOnly, SameSite=Strict');
  check(!(await page.evaluate(() => document.cookie)).includes('fleet_session'), 'scripts cannot read the session');
  const gt = truth();
  const want = Object.keys(gt.robots).length;
  await until(`the page shows ${want} robots`, () => model((n) => window.fleetDashboard.model.robots.size === n, want), 10000);
  await sleep(1000);
  const seen = await model(() => [...window.fleetDashboard.model.robots.values()].map((r) => [r.id, r.pose.x, r.pose.y]));
  const now = truth();
  let worst = 0;
  for (const [id, x, y] of seen) {
    const t = now.robots[id];
    worst = Math.max(worst, t ? Math.hypot(t[0] - x, t[1] - y) : Infinity);
  }
  check(seen.length === want && worst < 0.3,
        `${seen.length} robots on the page, ${want} in the simulator; farthest ${worst.toFixed(3)} m from ground truth`);
  await shot('2-live.png');

  // 2a. The people the robots see (the agents publish them; no ground truth in a deployment), drawn
  // as pink diamonds where the simulator has its person, and the contacts and near misses counted
  // from what the fleet reports.
  const people = await until('the page shows the people the robots see', () => model(() => {
    const seen = window.fleetDashboard.model.peopleSeen();
    return seen.length ? seen : null;
  }), 20000);
  if (people) {
    const h = Object.values(truth().humans || {});
    const off = Math.min(...people.map((p) => Math.min(...h.map((t) => Math.hypot(t[0] - p.x, t[1] - p.y)))));
    check(h.length > 0 && off < 0.6,
          `${people.length} people seen (by ${[...new Set(people.map((p) => p.robot))].join(', ')}), ${off.toFixed(2)} m from the simulator's person`);
    // The canvas is redrawn on the next animation frame after the model changes: a person that
    // moved since the last frame is not yet where the model has it (under load, frames come late).
    // Sampled until one person seen is pink where the model has it, for up to 10 s.
    const pink = await until('a person seen is drawn as a pink diamond', () => model(() => {
      const { view: v, model: m } = window.fleetDashboard;
      for (const p of m.peopleSeen()) {
        const [px, py] = v.toCanvas(p.x, p.y);
        const rgb = [...v.canvas.getContext('2d').getImageData(Math.round(px), Math.round(py), 1, 1).data].slice(0, 3);
        if (rgb[0] > 170 && rgb[1] < 120 && rgb[2] > 70 && rgb[2] < 170)
          return rgb;
      }
      return null;
    }), 10000);
    if (pink)
      check(true, `a person seen is drawn as a pink diamond (${JSON.stringify(pink)})`);
  }
  const figures = await until('the contacts and near-miss figures are shown', () => page.evaluate(() => {
    const f = {};
    const dl = document.getElementById('figure-list');
    for (const dt of dl.querySelectorAll('dt')) {
      f[dt.textContent] = dt.nextElementSibling ? dt.nextElementSibling.textContent : '';
    }
    return f.contacts && f.contacts.includes('robot–person') && f['near misses'].includes('robot–robot') ? f : null;
  }), 10000);
  if (figures) {
    const metrics = await page.evaluate(async () => (await fetch(new URL('../v1/metrics', location.href))).json());
    const px = metrics.proximity;
    check(px && figures.contacts.startsWith(`${px.robot_robot.contacts} robot–robot`),
          `contacts: ${figures.contacts}; near misses: ${figures['near misses']}; closest: ${figures.closest}; people seen: ${figures['people seen']}`);
  }
  await shot('2a-people-seen.png');
  const operatorActions = await page.evaluate(() =>
    [...document.querySelectorAll('[data-robot-action]')].filter((b) => !b.disabled).length);
  check(operatorActions === 4, `the operator is offered the robot's four actions (${operatorActions} enabled)`);

  // 2b. The traffic layer: the traffic manager's roadmap and its station queues, faint; the route
  // released to one robot (this test published it) solid, then dashed, in that robot's colour.
  const traffic = await until('the page has the roadmap, its station queues and the release', () => model((id) => {
    const m = window.fleetDashboard.model;
    const ok = m.roadmap && !m.roadmap.too_large && m.roadmap.queues.length > 0 && m.queues.length > 0 &&
      m.releases.has(id);
    return ok ? { nodes: m.roadmap.nodes.length / 2, queues: m.roadmap.queues.length, base: m.releases.get(id).base.length,
      horizon: m.releases.get(id).horizon.length } : null;
  }, released), 30000);
  if (traffic) {
    check(traffic.base === 5 && traffic.horizon === 4,
          `roadmap of ${traffic.nodes} nodes, ${traffic.queues} station queues; ${released}: ${traffic.base} nodes released, ${traffic.horizon} planned`);
    check(!(await page.$eval('#station-queues', (el) => el.hidden)), 'the station queues card is shown');
    await page.click('[data-layer=risk]'); // its colours are not what is looked for here
    await sleep(300);
    const routeOn = await routePixels(released);
    const lanesOn = await lanePixels();
    await page.click('[data-layer=routes]');
    await page.click('[data-layer=roadmap]');
    await sleep(500);
    const routeOff = await routePixels(released);
    const lanesOff = await lanePixels();
    await page.click('[data-layer=routes]');
    await page.click('[data-layer=roadmap]');
    await page.click('[data-layer=risk]');
    const inColour = routeOn.filter((p) => p.match).length;
    check(inColour >= routeOn.length / 2,
          `${released}'s released route is drawn in its colour (${inColour} of ${routeOn.length} points: ${JSON.stringify(routeOn.map((p) => p.rgb))})`);
    check(routeOff.filter((p) => p.match).length < inColour, 'the routes layer switches off');
    const changed = lanesOn.filter((p, i) => p.join() !== lanesOff[i].join()).length;
    check(changed >= lanesOn.length / 2, `the roadmap is drawn (${changed} of ${lanesOn.length} lane points change when its layer is off)`);
    check(lanesOn.every((p) => Math.min(...p) > 150), 'faintly (no lane point darker than 150)');
    await sleep(500);
    await shot('2b-traffic.png');
  }

  // 3. A task from the page's form (with its confirmation).
  await page.select('#task-pickup', 'P-2');
  await page.select('#task-dropoff', 'D-1');
  await page.click('#task-form button[type=submit]');
  await page.waitForSelector('#confirm[open]');
  const prompt = await page.$eval('#confirm-text', (el) => el.textContent);
  const taskId = (prompt.match(/task (ui-[^:]+):/) || [])[1];
  check(!!taskId, `the confirmation names the task (${prompt})`);
  await page.click('#confirm-ok');
  const robot = await until('the task is assigned and under way', () => model((id) => {
    const t = window.fleetDashboard.model.tasks.get(id);
    const active = t && ['assigned', 'en_route', 'loading', 'delivering', 'unloading'].includes(t.state);
    return active && t.robot ? t.robot : null;
  }, taskId), 60000);

  // 4. Pause its robot from the page: click it on the map, Pause, confirm.
  if (robot) {
    await sleep(1500); // let it drive a little
    // The robot drives on between reading its place and the click (by more than its disc when the
    // machine is loaded and the page draws late): try again where it is now, up to five times.
    for (let attempt = 1; ; ++attempt) {
      const at = await robotOnScreen(robot);
      await page.mouse.click(at[0], at[1]);
      try {
        await page.waitForFunction((id) => document.getElementById('robot-name').textContent === id, { timeout: 3000 }, robot);
        break;
      } catch (e) {
        if (attempt >= 5) throw e;
      }
    }
    await page.click('[data-robot-action=pause]');
    await page.waitForSelector('#confirm[open]');
    await page.click('#confirm-ok');
    await until('the page shows the robot paused', () => model((id) => {
      const r = window.fleetDashboard.model.robots.get(id);
      return r && r.paused && Math.abs(r.v) < 1e-3;
    }, robot), 20000);
    const a = truth();
    await sleep(3000); // ~15 s simulated
    const b = truth();
    const moved = Math.hypot(b.robots[robot][0] - a.robots[robot][0], b.robots[robot][1] - a.robots[robot][1]);
    check(b.t - a.t > 5 && moved < 0.02,
          `paused from the page, ${robot} moved ${moved.toFixed(3)} m in ${(b.t - a.t).toFixed(1)} s simulated`);
    await shot('3-paused.png');
    await page.click('[data-robot-action=resume]');
    await page.waitForSelector('#confirm[open]');
    await page.click('#confirm-ok');
    await until('the robot drives on after resume', () => model((id) => {
      const r = window.fleetDashboard.model.robots.get(id);
      return r && !r.paused;
    }, robot), 20000);
  }

  let multiId = null; // the multi-stop task submitted from the form in 4b
  // 4b. A waiting task changed from the queue's "change" dialog. Every robot is held through the
  // API (a held robot is given no task), so the task submitted then stays queued; it is given
  // priority 7 and a deadline 30 min ahead, and the adapter's task view has
  // both (the deadline from this computer's clock, as the adapter stamps created times). Then it is
  // cancelled and the robots are let go.
  {
    const api = async (method, p, body) => {
      const r = await fetch(`${direct.origin}${p}`, { method, headers: { authorization: `Bearer ${token}`,
        'content-type': 'application/json' }, body: body ? JSON.stringify(body) : undefined });
      return { status: r.status, body: await r.json().catch(() => ({})) };
    };
    const robots = Object.keys(truth().robots);
    const holds = await Promise.all(robots.map((r) => api('POST', `/v1/robots/${r}/pause`)));
    const held = `ui-held-${Date.now()}`;
    const posted = await api('POST', '/v1/tasks', { id: held, kind: 'transport', pickup: 'P-1', dropoff: 'D-2' });
    check(posted.status === 201 && holds.every((h) => h.status < 300),
          `a task to change is submitted while every robot is held (${posted.status}; ${holds.map((h) => h.status)})`);
    const button = `#queue tr[data-task="${held}"] button`;
    await until('the held task is listed with a change button', async () => {
      const labels = await page.$$eval(button, (bs) => bs.map((b) => b.textContent));
      return labels.includes('change');
    }, 20000);
    await page.evaluate((sel) => [...document.querySelectorAll(sel)].find((b) => b.textContent === 'change').click(), button);
    await page.waitForSelector('#change[open]');
    check((await page.$eval('#change-task', (el) => el.textContent)) === held, 'the change dialog names the task');
    await page.type('#change-priority', '7');
    await page.type('#change-deadline-min', '30');
    await shot('4b-change.png');
    await page.click('#change-ok');
    const changed = await until('the change reached the task', async () => {
      const v = await api('GET', `/v1/tasks/${held}`);
      return v.body.task && v.body.task.priority === 7 && v.body.task.deadline_ns > 0 ? v.body.task : null;
    }, 20000);
    const ahead = changed ? (changed.deadline_ns / 1e6 - Date.now()) / 60000 : 0;
    check(!!changed && Math.abs(ahead - 30) < 1,
          `priority 7 and a deadline ${ahead.toFixed(1)} min ahead (${changed && changed.deadline})`);
    await api('DELETE', `/v1/tasks/${held}`);
    // A multi-stop task from the form (kind "Multi-stop", its stops as text), stored with its
    // steps while the robots are still held; a robot carries it out once they are let go (6.).
    await page.select('#task-kind', 'multistop');
    await page.type('#task-steps', 'pick:P-1:L-9; drop:D-2:L-9; wait:::2');
    await page.click('#task-form button[type=submit]');
    await page.waitForSelector('#confirm[open]');
    const multiPrompt = await page.$eval('#confirm-text', (el) => el.textContent);
    multiId = (multiPrompt.match(/task (ui-[^:]+):/) || [])[1];
    check(!!multiId && multiPrompt.includes('pick P-1 L-9 → drop D-2 L-9 → wait'),
          `the confirmation names the stops (${multiPrompt})`);
    await page.click('#confirm-ok');
    const multi = await until('the multi-stop task is stored with its steps', async () => {
      const v = await api('GET', `/v1/tasks/${multiId}`);
      return v.status === 200 && v.body.task && v.body.task.steps ? v.body.task : null;
    }, 20000);
    check(!!multi && multi.kind === 'multistop' && multi.steps.length === 3 && multi.steps[1].load_id === 'L-9',
          `the multi-stop task from the form is stored with its 3 steps (${JSON.stringify(multi)})`);
    await page.select('#task-kind', 'transport');
    await Promise.all(robots.map((r) => api('POST', `/v1/robots/${r}/resume`)));
  }

  // 5. The adapter restarts: the page says so, reconnects and catches up. Sessions are kept by the
  // adapter (logging out revokes them), so a restarted adapter knows none: the page asks for the
  // token again, and once given it is live and catches up.
  fs.writeFileSync(path.join(dir, 'restart.request'), '1');
  await until('the page notices the lost connection', () => page.$eval('#status', (el) => el.textContent.includes('reconnecting') || el.textContent.includes('retrying')), 20000);
  await shot('4-adapter-restarting.png');
  await until('the page asks for the token again after the restart', async () => (await page.$('#login[open]')) !== null, 30000);
  await page.$eval('#login-token', (el) => { el.value = ''; });
  await page.type('#login-token', token);
  await page.click('#login-submit');
  await until('the page is live again after the restart', () => page.$eval('#status', (el) => el.textContent === 'live'), 30000);

  // 6. The task reaches done, as the page tells it.
  await until('the task submitted from the page is done', () => model((id) => {
    const t = window.fleetDashboard.model.tasks.get(id);
    return t && t.state === 'done';
  }, taskId), 150000);
  check(true, `task ${taskId} done`);
  const multiDone = await until('the multi-stop task from the form is done, stop by stop', async () => {
    const r = await fetch(`${direct.origin}/v1/tasks/${multiId}`, { headers: { authorization: `Bearer ${token}` } });
    const v = await r.json().catch(() => ({}));
    return v.state === 'done' ? v : null;
  }, 150000);
  check(!!multiDone && multiDone.step === 3, `the multi-stop task ${multiId} is done at its 3rd stop (${JSON.stringify(multiDone)})`);
  await page.mouse.click(5, 5);
  await shot('5-done.png');

  // 7. Under the proxy's prefix the page asked for nothing outside it (no absolute /v1/... URL).
  check(outside.length === 0, `every request stayed under ${kPrefix}/` +
                              (outside.length ? ` (outside: ${[...new Set(outside)].join(', ')})` : ''));
} catch (e) {
  check(false, `no exception: ${e.stack || e}`);
} finally {
  await browser.close();
  proxy.closeAllConnections();
  proxy.close();
}
process.exit(failures ? 1 : 0);
