// The side panels: figures, the selected robot and its actions, the task form, the task queue,
// the station queues and recent events. Updated from the model a few times a second, always
// through textContent (task ids and reasons come from outside and are never parsed as HTML).
// Actions the session's scopes do not allow are greyed out (the server would refuse them: 403),
// and robot actions while the fleet manager is unreachable (503).

import { stepsFromText } from './task_steps.js';

const QUEUE_ROWS = 100;
const EVENT_ROWS = 50;

export class Panels {
  constructor(model, view, { act, confirmThen }) {
    this.model = model;
    this.view = view;
    this.act = act;
    this.confirmThen = confirmThen;
    this.lastUpdate = 0;
    this.lastVersion = -1;
    this.selected = '';
    this.scopes = new Set(['read', 'submit', 'operate']); // until the session says otherwise
    this.who = '';

    view.canvas.addEventListener('click', (ev) => {
      const rect = view.canvas.getBoundingClientRect();
      this.select(view.robotAt(model, ev.clientX - rect.left, ev.clientY - rect.top));
    });
    for (const button of document.querySelectorAll('[data-robot-action]')) {
      button.addEventListener('click', () => this.robotAction(button.dataset.robotAction));
    }
    const kind = document.getElementById('task-kind');
    kind.addEventListener('change', () => {
      const multi = kind.value === 'multistop';
      for (const el of document.querySelectorAll('#task-form .transport-field')) el.hidden = multi;
      for (const el of document.querySelectorAll('#task-form .multistop-field')) el.hidden = !multi;
      document.getElementById('task-pickup').required = !multi;
      document.getElementById('task-dropoff').required = !multi;
    });
    document.getElementById('task-form').addEventListener('submit', (ev) => {
      ev.preventDefault();
      const priority = Number(document.getElementById('task-priority').value || 0);
      const id = 'ui-' + new Date().toISOString().replace(/[-:.TZ]/g, '').slice(0, 14) + '-' +
                 Math.floor(Math.random() * 1e4);
      let task;
      let what;
      if (kind.value === 'multistop') {
        const text = document.getElementById('task-steps').value;
        try {
          task = { id, kind: 'multistop', steps: stepsFromText(text) };
        } catch (e) {
          this.model.log(`task ${id}: ${e.message}`);
          return;
        }
        what = `multi-stop task ${id}: ${task.steps.map((s) => [s.action, s.station, s.load_id].filter(Boolean).join(' ')).join(' → ')}`;
      } else {
        const pickup = document.getElementById('task-pickup').value;
        const dropoff = document.getElementById('task-dropoff').value;
        task = { id, kind: 'transport', pickup, dropoff };
        what = `transport task ${id}: ${pickup} → ${dropoff}`;
      }
      if (priority) {
        task.priority = priority;
      }
      this.confirmThen(`Submit ${what}${priority ? ', priority ' + priority : ''}?`, () =>
        this.act(`task ${id}`, 'POST', '/v1/tasks', task));
    });
  }

  /** The change dialog for waiting task `id`: PATCH /v1/tasks/{id} with what was filled in. */
  changeTask(id) {
    const dlg = document.getElementById('change');
    document.getElementById('change-task').textContent = id;
    const priority = document.getElementById('change-priority');
    const minutes = document.getElementById('change-deadline-min');
    priority.value = '';
    minutes.value = '';
    dlg.returnValue = '';
    dlg.onclose = () => {
      if (dlg.returnValue !== 'ok') {
        return;
      }
      const body = {};
      if (priority.value !== '') {
        body.priority = Number(priority.value);
      }
      if (minutes.value !== '') {
        // As RFC 3339 from this computer's clock, as the adapter stamps a task's created time (a
        // simulation's fleet clock is simulated and would put the deadline before the task).
        const m = Number(minutes.value);
        if (m > 0) {
          body.deadline = new Date(Date.now() + m * 60000).toISOString();
        } else {
          body.deadline_ns = 0;
        }
      }
      if (!Object.keys(body).length) {
        this.model.log(`change ${id}: nothing to change`);
        return;
      }
      this.act(`change ${id}`, 'PATCH', `/v1/tasks/${encodeURIComponent(id)}`, body);
    };
    dlg.showModal();
  }

  /** What the session may do (GET /v1/session): actions needing another scope are greyed out. */
  setScopes(name, scopes) {
    this.who = name;
    this.scopes = new Set(scopes);
    for (const el of document.querySelectorAll('[data-scope]')) {
      this.gate(el, !!el.dataset.robotAction); // robot actions wait for a selected robot (robot())
    }
    const missing = ['submit', 'operate'].filter((s) => !this.scopes.has(s));
    const note = document.getElementById('scope-note');
    note.textContent = missing.length
      ? `Logged in as "${name}" without the ${missing.map((s) => `"${s}"`).join(' and ')} ` +
        `scope${missing.length > 1 ? 's' : ''}: ` +
        `${missing.includes('operate') ? 'robot actions' : ''}${missing.length === 2 ? ' and ' : ''}` +
        `${missing.includes('submit') ? 'submitting and cancelling tasks' : ''} are not offered.`
      : '';
    note.hidden = !missing.length;
    this.model.version++;
  }

  allowed(scope) {
    return this.scopes.has(scope);
  }

  /** Greys out `el` when its scope is missing (saying why), else when `otherwise` holds. */
  gate(el, otherwise, why = '') {
    const scope = el.dataset.scope;
    if (scope && !this.allowed(scope)) {
      el.disabled = true;
      el.title = `the token "${this.who}" lacks the "${scope}" scope`;
      return;
    }
    el.disabled = otherwise;
    el.title = otherwise ? why : '';
  }

  setStations(stations) {
    const fill = (id, kind) => {
      const sel = document.getElementById(id);
      sel.replaceChildren();
      for (const s of stations.filter((s) => s.kinds.includes(kind))) {
        sel.append(new Option(s.name, s.name));
      }
    };
    fill('task-pickup', 'pickup');
    fill('task-dropoff', 'dropoff');
  }

  select(id) {
    this.selected = id;
    this.view.selected = id;
    this.model.version++;
  }

  robotAction(action) {
    const id = this.selected;
    if (!id) {
      return;
    }
    const what = { pause: 'Pause', resume: 'Resume', home: 'Send home', charge: 'Send to charge' }[action];
    this.confirmThen(`${what}: robot ${id}?`, () =>
      this.act(`${action} ${id}`, 'POST', `/v1/robots/${encodeURIComponent(id)}/${action}`));
  }

  update(now) {
    if (this.model.version === this.lastVersion && now - this.lastUpdate < 1000) {
      return;
    }
    if (now - this.lastUpdate < 250) {
      return; // the DOM a few times a second is plenty; the canvas runs every frame
    }
    this.lastUpdate = now;
    this.lastVersion = this.model.version;
    this.figures(now);
    this.robot(now);
    this.queue();
    this.stationQueues();
    this.events();
  }

  figures(now) {
    fillList(document.getElementById('figure-list'), this.model.figures(now));
  }

  robot(now) {
    const r = this.model.robots.get(this.selected);
    document.getElementById('robot-name').textContent = r ? r.id : this.selected ? this.selected + ' (gone)' : '—';
    document.getElementById('robot-hint').hidden = !!r;
    const offline = !this.model.managerOnline;
    for (const b of document.querySelectorAll('[data-robot-action]')) {
      this.gate(b, !r || offline, offline ? 'the fleet manager is unreachable' : 'select a robot on the map');
    }
    if (!r) {
      fillList(document.getElementById('robot-details'), {});
      return;
    }
    const age = (now - r.receivedAt) / 1000;
    fillList(document.getElementById('robot-details'), {
      state: (r.fault ? 'FAULT' : r.mode) + (r.paused ? ' (paused)' : ''),
      task: r.task || '—',
      battery: `${Math.round(r.battery * 100)} %`,
      position: `${r.pose.x.toFixed(2)}, ${r.pose.y.toFixed(2)} m`,
      heading: `${Math.round(r.heading_deg)}°`,
      speed: `${r.v.toFixed(2)} m/s`,
      'people seen': String((r.people_seen || []).length),
      'pose σ': r.position_sigma < 0 || r.position_sigma > 100 ? 'unknown' : `${(r.position_sigma * 100).toFixed(1)} cm`,
      heard: age < 2 ? 'now' : `${age.toFixed(0)} s ago`,
    });
  }

  queue() {
    const open = this.model.openTasks().sort((a, b) => (a.stamp_ns || 0) - (b.stamp_ns || 0));
    document.getElementById('queue-count').textContent = `(${open.length})`;
    const body = document.querySelector('#queue tbody');
    const cancellable = this.allowed('submit');
    const offline = !this.model.managerOnline;
    const unreachable = 'the fleet manager is unreachable';
    this.gate(document.querySelector('#task-form button[type=submit]'), offline, unreachable);
    const rows = open.slice(0, QUEUE_ROWS).map((t) => {
      const tr = document.createElement('tr');
      tr.dataset.task = t.id;
      for (const text of [t.id, t.state || '?', t.robot || '', etaText(t.eta_ns, this.model.latestStampNs)]) {
        const td = document.createElement('td');
        td.textContent = text;
        tr.append(td);
      }
      const td = document.createElement('td');
      const button = (text, title, onClick) => {
        const b = document.createElement('button');
        b.type = 'button';
        b.textContent = text;
        b.dataset.scope = 'submit';
        b.disabled = offline;
        b.title = offline ? unreachable : title;
        b.addEventListener('click', onClick);
        td.append(b);
      };
      if (cancellable && (t.state === 'queued' || t.state === 'requeued')) {
        button('change', 'its priority or deadline', () => this.changeTask(t.id));
      }
      if (cancellable) {  // not offered at all without the scope: one greyed button per row is noise
        button('cancel', '', () =>
          this.confirmThen(`Cancel task ${t.id}?`, () =>
            this.act(`cancel ${t.id}`, 'DELETE', `/v1/tasks/${encodeURIComponent(t.id)}`)));
      }
      tr.append(td);
      return tr;
    });
    body.replaceChildren(...rows);
  }

  /** Who waits in line at each station (from the roadmap's queues; empty without a traffic manager). */
  stationQueues() {
    const card = document.getElementById('station-queues');
    const queues = this.model.queues || [];
    card.hidden = !this.model.roadmap;
    const body = document.querySelector('#station-queue-list tbody');
    const rows = queues
      .filter((q) => q.at || (q.waiting && q.waiting.length))
      .map((q) => {
        const tr = document.createElement('tr');
        for (const text of [q.station, q.at || '—', (q.waiting || []).join(' ← ') || '—']) {
          const td = document.createElement('td');
          td.textContent = text;
          tr.append(td);
        }
        return tr;
      });
    const waiting = queues.reduce((n, q) => n + ((q.waiting && q.waiting.length) || 0), 0);
    document.getElementById('station-queue-count').textContent = `(${waiting} waiting)`;
    const empty = document.getElementById('station-queue-empty');
    empty.hidden = rows.length > 0;
    empty.textContent = this.model.roadmap && this.model.roadmap.too_large
      ? 'The roadmap is too large to draw.' : 'Nobody waits at a station.';
    body.replaceChildren(...rows);
  }

  events() {
    const list = document.getElementById('events');
    const items = this.model.events.slice(-EVENT_ROWS).reverse().map((e) => {
      const li = document.createElement('li');
      li.textContent = `${e.at.toLocaleTimeString()} ${e.text}`;
      return li;
    });
    list.replaceChildren(...items);
  }
}

/** "in 42 s", "in 3 min", "due" (past), "" (no estimate): the ETA against the fleet's newest stamp. */
function etaText(etaNs, nowNs) {
  if (!etaNs) {
    return '';
  }
  const s = (etaNs - nowNs) / 1e9;
  if (s <= 0) {
    return 'due';
  }
  return s < 120 ? `in ${Math.round(s)} s` : `in ${Math.round(s / 60)} min`;
}

function fillList(dl, entries) {
  const nodes = [];
  for (const [k, v] of Object.entries(entries)) {
    const dt = document.createElement('dt');
    dt.textContent = k;
    const dd = document.createElement('dd');
    dd.textContent = v;
    nodes.push(dt, dd);
  }
  dl.replaceChildren(...nodes);
}
