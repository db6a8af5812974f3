// Drives the dashboard in Debian's chromium (puppeteer-core: no browser download) against a running
// fleet; run by tests/integration/dashboard/dashboard_browser_test.cpp, which starts the fleet,
// writes the simulator's ground truth to $DASH_DIR/truth.json and restarts the adapter when
// $DASH_DIR/restart.request appears. Exit 0 when every check passed; each check prints one line.
//
// Env: DASH_URL (the page), DASH_TOKEN (the adapter's bearer token), DASH_DIR, DASH_SHOTS (folder
// for the screenshots).

import fs from 'node:fs';
import path from 'node:path';
import puppeteer from 'puppeteer-core';

const url = process.env.DASH_URL;
const token = process.env.DASH_TOKEN;
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

// Root in CI: chromium's sandbox needs user namespaces it does not get there.
const browser = await puppeteer.launch({
  executablePath: '/usr/bin/chromium',
  headless: true,
  args: ['--no-sandbox', '--disable-gpu', '--disable-dev-shm-usage', '--no-first-run'],
});
try {
  const page = await browser.newPage();
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

  // 2. The right token: the robots, where the simulator has them.
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
    const at = await model((id) => {
      const v = window.fleetDashboard.view;
      const r = window.fleetDashboard.model.robots.get(id);
      const [px, py] = v.toCanvas(r.pose.x, r.pose.y);
      const rect = v.canvas.getBoundingClientRect();
      return [rect.left + px / v.dpr, rect.top + py / v.dpr];
    }, robot);
    await page.mouse.click(at[0], at[1]);
    await page.waitForFunction((id) => document.getElementById('robot-name').textContent === id, { timeout: 5000 }, robot);
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

  // 5. The adapter restarts: the page says so, reconnects and catches up.
  fs.writeFileSync(path.join(dir, 'restart.request'), '1');
  await until('the page notices the lost connection', () => page.$eval('#status', (el) => el.textContent.includes('reconnecting') || el.textContent.includes('retrying')), 20000);
  await shot('4-adapter-restarting.png');
  await until('the page is live again after the restart', () => page.$eval('#status', (el) => el.textContent === 'live'), 30000);

  // 6. The task reaches done, as the page tells it.
  await until('the task submitted from the page is done', () => model((id) => {
    const t = window.fleetDashboard.model.tasks.get(id);
    return t && t.state === 'done';
  }, taskId), 150000);
  check(true, `task ${taskId} done`);
  await page.mouse.click(5, 5);
  await shot('5-done.png');
} catch (e) {
  check(false, `no exception: ${e.stack || e}`);
} finally {
  await browser.close();
}
process.exit(failures ? 1 : 0);
