// The live operator dashboard: logs in (a session made from the bearer token), loads the site,
// follows the adapter's stream and draws the fleet; operator actions ask for confirmation first.

import { Api, ApiError, STREAM_EVENTS } from './api.js';
import { FleetModel } from './fleet_model.js';
import { LAYERS, MapView, MODE_COLOURS, robotColour } from './map_view.js';
import { Panels } from './panels.js';
import { RobotTimeCard } from './robot_time.js';

const api = new Api();
const model = new FleetModel();
const view = new MapView(document.getElementById('map'));
const panels = new Panels(model, view, { act, confirmThen });
const robotTime = new RobotTimeCard(api);
let closeStream = null;
let lastDrawVersion = -1;
let lastDrawAt = 0;
let animatingUntil = 0;
let glideMs = 300; // how long a robot takes to reach its new pose: the time between updates
let lastRobotsAt = 0;

window.fleetDashboard = {
  model,
  view,
  robotColour,
  ready: false,
  fps: (ms) => view.fps(ms),
  /** Feeds one stream message as if it came from the adapter (replay benchmarks). */
  inject: (name, data) => onMessage(name, data),
};

function setStatus(text, level = 'ok') {
  const el = document.getElementById('status');
  el.textContent = text;
  el.className = 'status' + (level === 'ok' ? '' : ' ' + level);
}

function onMessage(name, data) {
  const now = Date.now();
  if (name === 'snapshot') {
    model.snapshot(data, now);
    layerAvailability();
    model.log(`connected: ${model.robots.size} robots, ${model.openTasks().length} open tasks`);
  } else if (name === 'robots') {
    if (lastRobotsAt) {
      glideMs = 0.8 * glideMs + 0.2 * Math.min(1000, Math.max(50, now - lastRobotsAt));
    }
    lastRobotsAt = now;
    for (const r of data.robots || []) {
      const old = model.robots.get(r.id);
      r.from = old ? drawnPose(old, now) : r.pose;
      r.movedAt = now;
    }
    model.robotsUpdate(data.robots || [], now);
    if (data.fleet_manager) {
      model.managerOnline = data.fleet_manager !== 'unreachable';
    }
    animatingUntil = now + glideMs;
  } else if (name === 'task') {
    model.task(data);
  } else if (name === 'risk') {
    model.setRisk(data);
  } else if (name === 'roadmap') {
    model.setRoadmap(data);
    layerAvailability();
  } else if (name === 'releases') {
    model.releasesUpdate(data);
  } else if (name === 'queues') {
    model.setQueues(data);
  } else if (name === 'proximity') {
    model.setProximity(data);
  }
}

/** Robots glide to each new pose until the next update is due instead of jumping at the update rate. */
function drawnPose(r, now) {
  if (!r.from || !r.movedAt) {
    return r.pose;
  }
  const f = Math.min(1, (now - r.movedAt) / glideMs);
  let dt = r.pose.theta - r.from.theta;
  dt = Math.atan2(Math.sin(dt), Math.cos(dt));
  return {
    x: r.from.x + (r.pose.x - r.from.x) * f,
    y: r.from.y + (r.pose.y - r.from.y) * f,
    theta: r.from.theta + dt * f,
  };
}

function frame(t) {
  const now = Date.now();
  if (model.version !== lastDrawVersion || now < animatingUntil || now - lastDrawAt > 1000) {
    lastDrawVersion = model.version;
    lastDrawAt = now;
    const robots = new Map([...model.robots].map(([id, r]) => [id, { ...r, pose: drawnPose(r, now) }]));
    view.draw({
      robots,
      people: model.peopleSeen(),
      risk: model.risk,
      roadmap: model.roadmap,
      releases: model.releases,
      queues: model.queues,
    }, t);
    panels.update(now);
  }
  requestAnimationFrame(frame);
}

async function act(label, method, path, body) {
  try {
    const res = await api.request(method, path, body);
    model.log(`${label}: done` + (res.task ? ` (task ${res.task})` : res.id ? ` (${res.id})` : ''));
    setStatus('live');
    return res;
  } catch (e) {
    model.log(`${label}: ${e.message}`);
    if (e.status === 401) {
      showLogin('your session ended; log in again');
    } else {
      setStatus(`${label} failed — ${e.message}`, 'warn');
    }
    return null;
  }
}

function confirmThen(text, action) {
  const dlg = document.getElementById('confirm');
  document.getElementById('confirm-text').textContent = text;
  dlg.returnValue = '';
  dlg.onclose = () => {
    if (dlg.returnValue === 'ok') {
      action();
    }
  };
  dlg.showModal();
}

function showLogin(message) {
  if (closeStream) {
    closeStream();
    closeStream = null;
  }
  window.fleetDashboard.ready = false;
  setStatus('not logged in', 'bad');
  document.getElementById('login-error').textContent = message || '';
  document.getElementById('logout').hidden = true;
  document.getElementById('who').textContent = '';
  const dlg = document.getElementById('login');
  if (!dlg.open) {
    dlg.showModal();
  }
}

async function start() {
  try {
    const session = await api.session();
    document.getElementById('logout').hidden = session.auth !== 'session';
    document.getElementById('who').textContent =
      session.auth === 'off' ? 'no login (authentication off)' : `${session.name} · ${session.scopes.join(', ')}`;
    panels.setScopes(session.name, session.scopes);
    robotTime.start();
  } catch (e) {
    if (e.status === 401) {
      showLogin('');
      return;
    }
    setStatus(`cannot reach the adapter: ${e.message} — retrying`, 'bad');
    setTimeout(start, 2000);
    return;
  }
  try {
    const site = await api.request('GET', '/v1/site');
    document.getElementById('site-name').textContent = site.name || '';
    view.setSite(site);
    panels.setStations(site.stations || []);
  } catch (e) {
    model.log(`no site picture: ${e.message}`);
  }
  setStatus('connecting…', 'warn');
  const handlers = Object.fromEntries(STREAM_EVENTS.map((name) => [name, (d) => onMessage(name, d)]));
  closeStream = api.stream({
    ...handlers,
    snapshot: (d) => {
      onMessage('snapshot', d);
      window.fleetDashboard.ready = true;
      setStatus('live');
    },
    state: (text, level) => {
      setStatus(text, level);
      if (level !== 'ok') {
        model.log(text);
      }
    },
    unauthorized: () => showLogin('your session ended; log in again'),
  });
}

document.getElementById('login-form').addEventListener('submit', async (ev) => {
  ev.preventDefault();
  const input = document.getElementById('login-token');
  try {
    await api.login(input.value);
    input.value = '';
    document.getElementById('login').close();
    start();
  } catch (e) {
    document.getElementById('login-error').textContent = e instanceof ApiError ? e.message : String(e);
  }
});

document.getElementById('logout').addEventListener('click', async () => {
  try {
    await api.logout();
  } finally {
    showLogin('logged out');
  }
});

const legend = document.getElementById('legend');
for (const [mode, colour] of Object.entries(MODE_COLOURS)) {
  const span = document.createElement('span');
  const dot = document.createElement('i');
  dot.style.background = colour;
  span.append(dot, mode);
  legend.append(span);
}
const personKey = document.createElement('span');
const personMark = document.createElement('i');
personMark.className = 'person';
personKey.append(personMark, 'person seen (by a robot)');
legend.append(personKey);
const riskKey = document.createElement('span');
riskKey.textContent = '· risk iso-levels: yellow (low) to red (high)';
legend.append(riskKey);
const routeKey = document.createElement('span');
routeKey.id = 'route-key';
const solid = document.createElement('i');
solid.className = 'swatch';
const dashed = document.createElement('i');
dashed.className = 'swatch dashed';
routeKey.append('· routes in each robot\'s colour (its ring): ', solid, 'released ', dashed, 'planned');
legend.append(routeKey);

// Layer switches, remembered in this browser.
const layerBoxes = {};
for (const [key, label] of Object.entries(LAYERS)) {
  const stored = localStorage.getItem('fleet.layer.' + key);
  view.layers[key] = stored === null ? true : stored === '1';
  const box = document.createElement('input');
  box.type = 'checkbox';
  box.checked = view.layers[key];
  box.dataset.layer = key;
  box.addEventListener('change', () => {
    view.layers[key] = box.checked;
    localStorage.setItem('fleet.layer.' + key, box.checked ? '1' : '0');
    model.version++;
  });
  const row = document.createElement('label');
  row.append(box, ' ' + label);
  document.getElementById('layers').append(row);
  layerBoxes[key] = row;
}

/** The traffic layers say when there is nothing to show (no traffic manager: reactive traffic). */
function layerAvailability() {
  const why = !model.roadmap ? 'no roadmap: the fleet runs without a traffic manager'
    : model.roadmap.too_large ? 'the roadmap is too large to draw' : '';
  for (const key of ['roadmap', 'routes', 'queues']) {
    layerBoxes[key].classList.toggle('unavailable', !!why);
    layerBoxes[key].title = why;
  }
  document.getElementById('route-key').hidden = !!why;
}
layerAvailability();

requestAnimationFrame(frame);
start();
