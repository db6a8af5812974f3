// A multi-stop task's steps as an operator types them (the same form as fleetctl's CSV column):
// `;`-separated steps, each `action:station[:load id[:seconds]]`, e.g.
// `pick:P-1:L-42; drop:D-2:L-42; wait:::5; goto:X; charge:C-1`. The server checks what they mean.

/** The steps of `text` as the API takes them; throws an Error naming the step that is malformed. */
export function stepsFromText(text) {
  const steps = [];
  text.split(';').map((s) => s.trim()).filter((s) => s !== '').forEach((one, i) => {
    const parts = one.split(':').map((p) => p.trim());
    if (parts.length > 4 || parts[0] === '') {
      throw new Error(`stop ${i + 1} "${one}": expected action:station[:load id[:seconds]]`);
    }
    const step = { action: parts[0] };
    if (parts[1]) step.station = parts[1];
    if (parts[2]) step.load_id = parts[2];
    if (parts[3]) {
      const s = Number(parts[3]);
      if (!Number.isFinite(s) || s < 0) {
        throw new Error(`stop ${i + 1}: expected seconds >= 0, got "${parts[3]}"`);
      }
      step.duration_ns = Math.round(s * 1e9);
    }
    steps.push(step);
  });
  if (steps.length === 0) {
    throw new Error('no stops: give at least one, e.g. goto:P-1');
  }
  return steps;
}
