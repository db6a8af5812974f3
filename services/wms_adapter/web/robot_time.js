// The robot-time card: where the fleet's time went since the adapter started (GET
// /v1/fleet/robot-time, the robot-time ledger), as one stacked bar of the nine categories with
// their shares and a thin bar per robot, refreshed every few seconds. Text through textContent only.

const CATEGORIES = [
  ['no_task', 'no task', '#b7bcc8'],
  ['driving', 'driving', '#2f6fde'],
  ['turning_docking', 'turning / docking', '#7fb0ff'],
  ['dwelling', 'dwelling', '#1f9d55'],
  ['waiting_on_robot', 'waiting on a robot', '#f0a020'],
  ['held_by_person', 'held by a person', '#d9480f'],
  ['held_by_safety', 'held by safety', '#a61e4d'],
  ['charging', 'charging', '#7a3fd1'],
  ['faulted', 'faulted', '#222'],
];

export class RobotTimeCard {
  constructor(api, { everyMs = 5000 } = {}) {
    this.api = api;
    this.everyMs = everyMs;
    this.bar = document.getElementById('robot-time-bar');
    this.keys = document.getElementById('robot-time-keys');
    this.total = document.getElementById('robot-time-total');
    this.timer = null;
  }

  start() {
    if (this.timer === null) {
      this.refresh();
      this.timer = setInterval(() => this.refresh(), this.everyMs);
    }
  }

  async refresh() {
    let data;
    try {
      data = await this.api.request('GET', '/v1/fleet/robot-time');
    } catch (e) {
      this.total.textContent = `(${e.message})`;
      return;
    }
    this.draw(data.fleet, data.robots.length);
    this.drawRobots(data.robots);
  }

  // The parts of one ledger as spans of a stacked bar (only the categories with time).
  static fill(bar, ledger) {
    bar.replaceChildren();
    for (const [key, label, colour] of CATEGORIES) {
      const share = ledger.shares[key] || 0;
      if (share > 0) {
        const part = document.createElement('span');
        part.style.width = `${(100 * share).toFixed(2)}%`;
        part.style.background = colour;
        part.title = `${label}: ${(100 * share).toFixed(1)} %`;
        part.dataset.activity = key;
        bar.append(part);
      }
    }
  }

  // Each robot's own bar, most "no task" first: the robots the fleet leaves without work on top.
  drawRobots(robots) {
    const rows = document.getElementById('robot-time-robots');
    if (rows === null) {
      return;
    }
    rows.replaceChildren();
    const byIdle = [...robots].sort((a, b) => (b.shares.no_task || 0) - (a.shares.no_task || 0) ||
      String(a.id).localeCompare(String(b.id)));
    for (const r of byIdle) {
      const name = document.createElement('span');
      name.className = 'robot-id';
      name.textContent = r.id;
      const bar = document.createElement('div');
      bar.className = 'stacked-bar';
      bar.dataset.robot = r.id;
      bar.dataset.seconds = String(r.seconds || 0);  // 0: listed, nothing filed yet (an empty bar)
      RobotTimeCard.fill(bar, r);
      rows.append(name, bar);
    }
  }

  draw(fleet, robots) {
    const hours = fleet.seconds / 3600;
    this.total.textContent =
      `${robots} robot${robots === 1 ? '' : 's'}, ${hours >= 1 ? hours.toFixed(1) + ' robot-h' : Math.round(fleet.seconds) + ' robot-s'}`;
    RobotTimeCard.fill(this.bar, fleet);
    this.keys.replaceChildren();
    for (const [key, label, colour] of CATEGORIES) {
      const share = fleet.shares[key] || 0;
      const item = document.createElement('li');
      const dot = document.createElement('i');
      dot.style.background = colour;
      item.append(dot, `${label} ${Math.round(100 * share)} %`);
      this.keys.append(item);
    }
  }
}
