// SPDX-License-Identifier: MIT
// The page of `ballbar serve` (docs/webui.md). It shows what the server's procedure says and sends the
// operator's button presses; every decision (the steps, the verdicts, the results) is the server's.
'use strict';

const $ = (id) => document.getElementById(id);
const token = new URLSearchParams(location.search).get('token') || '';
const client = Array.from(crypto.getRandomValues(new Uint8Array(12)), (b) => b.toString(16).padStart(2, '0')).join('');
const kArmMs = 700;  // a new question's buttons wait this long: a click meant for the last one is not its answer

function withToken(path) {
  return token ? path + (path.includes('?') ? '&' : '?') + 'token=' + encodeURIComponent(token) : path;
}

async function api(path, body) {
  const init = { headers: { 'X-Ballbar-Client': client } };
  if (token) init.headers.Authorization = 'Bearer ' + token;
  if (body !== undefined) {
    init.method = 'POST';
    init.headers['Content-Type'] = 'application/json';
    init.body = JSON.stringify(body);
  }
  const r = await fetch(path, init);
  const j = await r.json().catch(() => ({}));
  if (!r.ok) throw new Error(j.error || r.status + ' ' + r.statusText);
  return j;
}

function el(tag, text, cls) {
  const e = document.createElement(tag);
  if (text !== undefined && text !== null) e.textContent = text;
  if (cls) e.className = cls;
  return e;
}

// The stored units as the operator reads them.
const kUnits = { um: 'µm', um_per_m: 'µm/m', um_per_h: 'µm/h', ppm_per_K: 'ppm/K', deg: '°', hz: 'Hz', urad: 'µrad', urad_per_h: 'µrad/h', um_per_K: 'µm/K' };
function unit(u) { return kUnits[u] || u; }

function fmt(v, digits) {
  return v === null || v === undefined || Number.isNaN(v) ? '–' : Number(v).toFixed(digits);
}

function clock(s) {
  if (!(s > 0)) return '0:00';
  const m = Math.floor(s / 60), r = Math.floor(s % 60);
  return m + ':' + String(r).padStart(2, '0');
}

// ---- the procedure ----------------------------------------------------------------------------------

let state = null;          // the server's last snapshot
let stateAt = 0;           // when it came (the page's clock)
let showStart = true;      // the start panel, between procedures
let armedQuestion = 0;     // the question whose buttons are armed
let liveCount = 0, liveRate = 0;

function startError(msg) {
  $('start-error').textContent = msg;
  $('start-error').hidden = !msg;
}

async function start(body) {
  startError('');
  try {
    await api('/api/procedure', body);
    showStart = false;
    render();
  } catch (e) {
    startError(e.message);
  }
}

function readFile(input) {
  return new Promise((resolve, reject) => {
    const f = input.files[0];
    if (!f) return reject(new Error('choose the ' + input.id.replace('s-', '').replace('-', ' ')));
    const r = new FileReader();
    r.onload = () => resolve(r.result);
    r.onerror = () => reject(new Error('cannot read ' + f.name));
    r.readAsText(f);
  });
}

// Why a session is in its state, said once ("interrupted: interrupted by the operator" reads "by the operator").
function stateReason(m) {
  let r = m.state_reason || '';
  for (let i = 0; i < 2; ++i) {
    if (r.startsWith(m.state + ': ')) r = r.slice(m.state.length + 2);
    else if (r.startsWith(m.state + ' ')) r = r.slice(m.state.length + 1);
  }
  return r;
}

// A demo's pulled cable: the emulated instrument goes silent 20 s into the measurement (its own clock)
// and answers again 6 s later (the emulator's "faults", docs/emulator.md).
const PULLED_CABLE = { disconnect_at_s: 20, disconnect_s: 6 };

function circularRequest(demo) {
  const body = { procedure: 'circular', demo, plane: $('c-plane').value,
    radius_mm: Number($('c-radius').value), feed_mm_min: Number($('c-feed').value) };
  if (!demo) {
    body.device = $('c-device').value.trim();
    body.dialect = $('c-dialect').value;
  } else if ($('c-pull').checked) {
    body.faults = PULLED_CABLE;
  }
  return body;
}

$('start-circular-demo').onclick = () => start(circularRequest(true));
$('start-circular').onclick = () => start(circularRequest(false));
$('start-ssm-demo').onclick = () => start(Object.assign({ procedure: 'ssm', demo: true, machine: $('s-machine').value },
  $('s-pull').checked ? { faults: PULLED_CABLE } : {}));
$('start-ssm').onclick = async () => {
  try {
    const machine_file = await readFile($('s-machine-file'));
    const plan_file = await readFile($('s-plan-file'));
    start({ procedure: 'ssm', device: $('s-device').value.trim(), machine_file, plan_file });
  } catch (e) {
    startError(e.message);
  }
};

// Stop asks twice: the button, then the modal's own button.
$('stop').onclick = () => { $('confirm-stop').hidden = false; };
$('stop-no').onclick = () => { $('confirm-stop').hidden = true; };
$('stop-yes').onclick = async () => {
  $('confirm-stop').hidden = true;
  try { await api('/api/procedure/stop', {}); } catch (e) { alert(e.message); }
};
$('new-procedure').onclick = () => { showStart = true; render(); };
$('open-session').onclick = () => { if (state && state.session) location.hash = '#/session/' + state.session; };

async function answer(q, i) {
  try {
    await api('/api/procedure/answer', { question: q.id, option: i });
  } catch (e) {
    $('not-yet-note').hidden = false;
    $('not-yet-note').textContent = e.message;
  }
}

const kDangerous = ['abort', 'stop'];

function renderQuestion(q) {
  const box = $('answers');
  if (!q) {
    box.replaceChildren();
    $('prompt').textContent = state.running ? 'Measuring: nothing to do but watch the machine.' : '';
    $('not-yet-note').hidden = true;
    return;
  }
  if (box.dataset.q === String(q.id)) return;
  box.dataset.q = String(q.id);
  $('prompt').textContent = q.prompt;
  $('not-yet-note').hidden = true;
  $('not-yet-note').textContent = 'Take your time: the question stays here until you answer it.';
  const buttons = [];
  q.options.forEach((label, i) => {
    const text = label.replace(/-/g, ' ');
    const b = el('button', text.charAt(0).toUpperCase() + text.slice(1), kDangerous.includes(label) ? 'danger' : 'primary');
    b.type = 'button';
    b.dataset.option = String(i);
    b.disabled = true;
    b.onclick = () => {
      if (kDangerous.includes(label)) {  // asks twice, as the stop button
        $('confirm-option-title').textContent = q.prompt;
        $('option-yes').textContent = 'Yes, ' + label;
        $('option-yes').onclick = () => { $('confirm-option').hidden = true; answer(q, i); };
        $('confirm-option').hidden = false;
        return;
      }
      answer(q, i);
    };
    buttons.push(b);
  });
  if (q.not_yet) {
    const b = el('button', q.not_yet, 'secondary');
    b.type = 'button';
    b.id = 'not-yet';
    b.onclick = () => { $('not-yet-note').hidden = false; };  // answers nothing
    buttons.push(b);
  }
  box.replaceChildren(...buttons);
  armedQuestion = 0;
  setTimeout(() => {
    if (box.dataset.q !== String(q.id)) return;
    armedQuestion = q.id;
    box.querySelectorAll('button').forEach((b) => { b.disabled = !state.you_steer; });
  }, kArmMs);
}

function sketch(step, q) {
  const what = q ? q.what : '';
  const socket = state.socket_mm ? state.socket_mm.map((v) => fmt(v, 1)).join(', ') : null;
  const svg = (body, caption) =>
    '<svg viewBox="0 0 320 170" role="img" aria-label="' + caption + '">' + body + '</svg><p class="caption">' + caption + '</p>';
  if (what === 'reference' || what === 'reference-declined')
    return svg('<rect x="40" y="70" width="240" height="30" rx="6" class="s-cal"/><rect x="60" y="78" width="200" height="14" rx="7" class="s-bar"/>' +
      '<circle cx="60" cy="85" r="12" class="s-ball"/><circle cx="260" cy="85" r="12" class="s-ball"/>',
      'The bar in its calibrator: the reference (zero) is set there.');
  if (what === 'setup' || what === 'program-stop')
    return svg('<rect x="20" y="130" width="280" height="20" class="s-table"/><rect x="130" y="112" width="30" height="18" class="s-socket"/>' +
      '<circle cx="145" cy="106" r="9" class="s-ball"/><line x1="145" y1="106" x2="225" y2="40" class="s-barline"/>' +
      '<circle cx="225" cy="40" r="9" class="s-ball"/><rect x="213" y="0" width="24" height="30" class="s-spindle"/>',
      socket ? 'Socket on the table at (' + socket + ') mm; the bar between it and the tool ball.'
             : 'Socket on the table at the circle centre; the bar between it and the tool ball.');
  if (what === 'run-program' || what === 'run-part-program')
    return svg('<rect x="40" y="15" width="240" height="120" rx="8" class="s-screen"/>' +
      '<text x="60" y="45" class="s-code">O1000 (ballbar)</text><text x="60" y="68" class="s-code">G90 G17 G21</text>' +
      '<text x="60" y="91" class="s-code">…</text><circle cx="250" cy="150" r="16" class="s-cycle"/>' +
      '<text x="212" y="156" class="s-label">CYCLE START</text>',
      'Load the program on the controller, then press cycle start.');
  if (step === 5) return svg('<polyline points="30,140 80,90 130,110 180,50 230,70 290,30" class="s-chart"/>', 'The results, for you to accept.');
  return '';
}

function render() {
  if (!state) return;
  const idle = !state.running && (showStart || state.state === 'idle');
  $('start').hidden = !idle;
  $('run').hidden = idle;
  $('stop').hidden = !(state.running && state.you_steer);
  $('watching').hidden = !(state.running && !state.you_steer);
  if (idle) return;
  const step = state.step || { n: 1, of: 6, name: 'Connect' };
  const steps = $('steps');
  steps.replaceChildren(...(state.steps || []).map((name, i) => {
    const li = el('li', name, i + 1 < step.n ? 'done' : i + 1 === step.n ? 'current' : '');
    return li;
  }));
  $('step-title').textContent = 'Step ' + step.n + ' of ' + step.of + ': ' + step.name +
    (state.procedure === 'circular' ? ' — circular test' : ' — two-step SSM') + (state.demo ? ' (demo)' : '');
  renderQuestion(state.question);
  $('program-link').hidden = !(state.question && (state.question.what === 'run-program' || state.question.what === 'run-part-program') && state.program);
  $('program-download').href = withToken('/api/procedure/program');
  $('sketch').innerHTML = sketch(step.n, state.question);
  $('lost').hidden = !state.lost;
  $('finished').hidden = state.running;
  $('question').hidden = !state.running;
  if (!state.running) {
    $('finished-message').textContent = state.message || '';
    $('finished-message').className = state.state === 'completed' ? 'ok' : 'error';
    $('open-session').hidden = !state.session;
  }
  const tbody = $('points').tBodies[0];
  if (tbody.rows.length !== (state.points || []).length) {
    tbody.replaceChildren(...state.points.map((p) => {
      const tr = el('tr');
      [p.test, p.step, p.point, fmt(p.deviation_um, 2), fmt(p.std_um, 2), p.verdict].forEach((v) => tr.append(el('td', v)));
      tr.lastChild.className = p.verdict === 'ok' ? 'ok' : 'warn';
      return tr;
    }));
  }
  $('log').replaceChildren(...(state.log || []).map((l) => el('li', fmt(l.t_s, 1) + ' s  ' + l.text)));
  tick();
}

// The clocks keep counting between the server's messages.
function tick() {
  if (!state || !state.running) { $('time-left').textContent = ''; return; }
  const since = (state.now_ms + (Date.now() - stateAt)) / 1000;
  const g = state.progress || {};
  const measuring = state.step && state.step.n === 4;
  if (measuring && g.time_left_s > 0) {
    const left = g.time_left_s - (since - g.at_ms / 1000);
    $('time-left').textContent = 'Program time left: ' + clock(left) + ' at 100 % feed' +
      (g.total ? ' · ' + g.done + ' of ' + g.total + ' points' : '');
  } else {
    $('time-left').textContent = 'Elapsed ' + clock(since) + (g.total ? ' · ' + g.done + ' of ' + g.total + (state.procedure === 'circular' ? ' runs' : ' points') : '');
  }
  if (state.lost) $('lost-left').textContent = clock(state.lost.timeout_s - (since - state.lost.at_ms / 1000));
}
setInterval(tick, 250);
setInterval(() => { liveRate = liveCount; liveCount = 0; $('live-rate').textContent = liveRate + ' readings/s on this screen'; }, 1000);

function renderLive(l) {
  if (l.bar_mm === 0 && l.expected_mm === 0) {  // the procedure has no reading yet
    $('live-um').textContent = '–';
    $('live-mm').textContent = 'no reading yet';
    return;
  }
  ++liveCount;
  const dev = (l.bar_mm - l.expected_mm) * 1000;
  $('live-um').textContent = (dev >= 0 ? '+' : '') + dev.toFixed(1) + ' µm';
  $('live-um').className = 'live-um' + (l.out_of_range ? ' out' : '');
  $('live-mm').textContent = 'bar ' + l.bar_mm.toFixed(4) + ' mm, expected ' + l.expected_mm.toFixed(4) + ' mm';
  // The bar graph spans the instrument's range (±1 mm drawn when it does not say its range).
  const range_um = l.range_mm > 0 ? l.range_mm * 1000 : 1000;
  const frac = Math.max(-1, Math.min(1, dev / range_um));
  const fill = $('bar-fill');
  fill.style.left = (50 + Math.min(0, frac) * 50) + '%';
  fill.style.width = Math.abs(frac) * 50 + '%';
  $('live-range').textContent = l.out_of_range ? 'OUT OF RANGE' + (l.range_mm > 0 ? ' (beyond ±' + range_um.toFixed(0) + ' µm)' : '')
    : l.range_mm > 0 ? 'range ±' + range_um.toFixed(0) + ' µm' : 'the instrument does not say its range: ±1000 µm drawn';
}

function connect() {
  const es = new EventSource(withToken('/api/events?client=' + client));
  es.onopen = () => { $('link').textContent = 'connected'; $('link').className = 'link ok'; };
  es.onerror = () => { $('link').textContent = 'reconnecting…'; $('link').className = 'link bad'; };
  es.addEventListener('state', (e) => {
    const before = state;
    state = JSON.parse(e.data);
    stateAt = Date.now();
    if (state.running && (!before || !before.running)) showStart = false;
    render();
    if (!state.running && before && before.running && route().view === 'sessions') loadSessions();
  });
  es.addEventListener('live', (e) => renderLive(JSON.parse(e.data)));
}

// ---- sessions ---------------------------------------------------------------------------------------

let sessions = [];

function fillSelect(sel, values) {
  const keep = sel.value;
  sel.replaceChildren(el('option', 'all'), ...[...new Set(values)].sort().map((v) => el('option', v)));
  sel.firstChild.value = '';
  sel.value = keep;
}

function machineName(s) { return s.machine_asset_id || s.machine.type + (s.machine.name ? ' ' + s.machine.name : ''); }

function renderSessions() {
  fillSelect($('f-machine'), sessions.map(machineName));
  fillSelect($('f-procedure'), sessions.map((s) => s.procedure));
  fillSelect($('f-state'), sessions.map((s) => s.state));
  const f = { m: $('f-machine').value, p: $('f-procedure').value, s: $('f-state').value, from: $('f-from').value, to: $('f-to').value };
  const shown = sessions.filter((s) => (!f.m || machineName(s) === f.m) && (!f.p || s.procedure === f.p) &&
    (!f.s || s.state === f.s) && (!f.from || s.started_at.slice(0, 10) >= f.from) && (!f.to || s.started_at.slice(0, 10) <= f.to));
  const row = (s) => {
    const tr = el('tr');
    tr.dataset.session = s.id;
    [s.id, s.started_at.replace('T', ' ').slice(0, 19), s.procedure, machineName(s), s.state + (s.resumable ? ' (resumable)' : ''),
      s.point_count !== undefined ? s.point_count : (s.points !== undefined ? s.points : ''), s.operator || ''].forEach((v) => tr.append(el('td', v)));
    tr.onclick = () => { location.hash = '#/session/' + s.id; };
    return tr;
  };
  loadTrend(f.m);
  $('sessions').tBodies[0].replaceChildren(...shown.filter((s) => s.source !== 'emulator').reverse().map(row));
  $('demo-sessions').tBodies[0].replaceChildren(...shown.filter((s) => s.source === 'emulator').reverse().map(row));
}

// The trend of the machine chosen in the filter: one small chart a figure, its sessions left to right.
const kFigures = { G_um: 'G, µm', G_b_um: 'G(b), µm', backlash_x_um: 'backlash X, µm', backlash_y_um: 'backlash Y, µm',
  backlash_z_um: 'backlash Z, µm', squareness_um_per_m: 'squareness, µm/m', dV_max_um: 'largest |ΔV|, µm',
  d_alpha_arcsec: 'Δα, arcsec', d_beta_arcsec: 'Δβ, arcsec', d_gamma_arcsec: 'Δγ, arcsec' };

// Text into markup: stored text is anyone's (an imported file's dates, names).
function esc(t) { return String(t).replace(/[&<>"']/g, (c) => '&#' + c.charCodeAt(0) + ';'); }

function chart(title, pts) {
  const w = 300, h = 150, pad = 30;
  const vs = pts.map((p) => p.v), lo = Math.min(...vs), hi = Math.max(...vs), span = hi - lo || Math.abs(hi) || 1;
  const x = (i) => pad + (pts.length > 1 ? i * (w - 2 * pad) / (pts.length - 1) : (w - 2 * pad) / 2);
  const y = (v) => (hi === lo ? h / 2 : h - pad - (v - lo) / span * (h - 2 * pad));  // one value: mid-height
  let svg = '<svg viewBox="0 0 ' + w + ' ' + h + '" class="trend-chart" role="img" aria-label="' + title + '">' +
    '<text x="6" y="16" class="t-title">' + title + '</text>' +
    '<text x="6" y="' + (pad + 4) + '" class="t-axis">' + fmt(hi, 2) + '</text>' +
    '<text x="6" y="' + (h - pad + 4) + '" class="t-axis">' + fmt(lo, 2) + '</text>' +
    '<polyline class="t-line" points="' + pts.map((p, i) => x(i) + ',' + y(p.v)).join(' ') + '"/>';
  pts.forEach((p, i) => {
    svg += '<circle cx="' + x(i) + '" cy="' + y(p.v) + '" r="4" class="' + (p.demo ? 't-demo' : 't-real') + '"><title>session ' +
      p.session + ', ' + esc(p.at.slice(0, 10)) + ': ' + fmt(p.v, 3) + '</title></circle>';
  });
  return svg + '<text x="' + pad + '" y="' + (h - 8) + '" class="t-axis">' + esc(pts[0].at.slice(0, 10)) + '</text>' +
    '<text x="' + (w - pad - 70) + '" y="' + (h - 8) + '" class="t-axis">' + esc(pts[pts.length - 1].at.slice(0, 10)) + '</text></svg>';
}

async function loadTrend(machine) {
  $('trend').hidden = !machine;
  if (!machine) return;
  $('trend-title').textContent = 'Trend of ' + machine;
  try {
    const t = await api('/api/trend?machine=' + encodeURIComponent(machine));
    const charts = [];
    for (const [key, title] of Object.entries(kFigures)) {
      const pts = t.points.filter((p) => key in p.figures).map((p) => ({ v: p.figures[key], session: p.session, at: p.started_at, demo: p.demo }));
      if (pts.length) charts.push(chart(title, pts));
    }
    $('trend-charts').innerHTML = charts.length ? charts.join('') : '<p>No completed session of this machine holds a result.</p>';
  } catch (e) {
    $('trend-charts').textContent = e.message;
  }
}

async function loadSessions() {
  try {
    sessions = await api('/api/sessions');
    renderSessions();
  } catch (e) {
    $('sessions').tBodies[0].replaceChildren(el('tr', e.message, 'error'));
  }
}
['f-machine', 'f-procedure', 'f-state', 'f-from', 'f-to'].forEach((id) => { $(id).onchange = renderSessions; });

function kv(table, rows) {
  table.replaceChildren(...rows.map(([k, v]) => {
    const tr = el('tr');
    tr.append(el('th', k), el('td', v === null || v === undefined || v === '' ? '–' : v));
    return tr;
  }));
}

function polar(c) {
  const cv = $('polar'), g = cv.getContext('2d');
  const w = cv.width, mid = w / 2, R = w * 0.32, ring = w * 0.12;
  const half = c.polar_plot.deviation_um_at_outer_ring;
  const r = (dev) => R + (dev / half) * ring;
  g.clearRect(0, 0, w, w);
  g.lineWidth = 1;
  if (c.tolerance && c.tolerance.circularity_um) {  // the band: the tolerance around the mean circle
    const t = c.tolerance.circularity_um / 2;
    g.fillStyle = 'rgba(40,160,80,0.12)';
    g.beginPath(); g.arc(mid, mid, r(t), 0, 2 * Math.PI); g.arc(mid, mid, Math.max(1, r(-t)), 0, 2 * Math.PI, true); g.fill();
  }
  g.strokeStyle = '#999';
  for (const d of [-half, 0, half]) { g.beginPath(); g.arc(mid, mid, r(d), 0, 2 * Math.PI); g.stroke(); }
  g.fillStyle = '#555'; g.font = '13px sans-serif';
  g.fillText('+' + half + ' µm', mid + r(half) * 0.71 + 4, mid - r(half) * 0.71);
  g.fillText((-half) + ' µm', mid + 4, mid - r(-half) + 14);
  const colours = { ccw: '#1f5fbf', cw: '#c0392b' };
  c.runs.forEach((run) => {
    g.strokeStyle = colours[run.direction] || '#333'; g.lineWidth = 1.5; g.beginPath();
    run.polar.angle_deg.forEach((a, i) => {
      const rad = a * Math.PI / 180, rr = r(run.polar.deviation_um[i]);
      const x = mid + rr * Math.cos(rad), y = mid - rr * Math.sin(rad);
      if (i) g.lineTo(x, y); else g.moveTo(x, y);
    });
    g.stroke();
  });
  // Each run's diagnosed model, dashed and darker over its run: where the run leaves it, no diagnostic explains.
  const models = { ccw: '#0b2f66', cw: '#6b1a12' };
  let withModel = 0;
  c.runs.forEach((run) => {
    const a = run.polar.model_angle_deg || [], d = run.polar.model_deviation_um || [];
    if (a.length < 2 || a.length !== d.length) return;
    withModel++;
    g.strokeStyle = models[run.direction] || '#000'; g.lineWidth = 1.5; g.setLineDash([6, 4]); g.beginPath();
    a.forEach((deg, i) => {
      const rad = deg * Math.PI / 180, rr = r(d[i]);
      const x = mid + rr * Math.cos(rad), y = mid - rr * Math.sin(rad);
      if (i) g.lineTo(x, y); else g.moveTo(x, y);
    });
    g.stroke(); g.setLineDash([]);
  });
  g.font = '14px sans-serif';
  c.runs.forEach((run, i) => { g.fillStyle = colours[run.direction]; g.fillText(run.direction + ': G ' + fmt(run.circularity_um, 1) + ' µm', 10, 20 + 18 * i); });
  if (withModel) { g.fillStyle = '#333'; g.fillText('dashed: the diagnosed model', 10, 20 + 18 * c.runs.length); }
}

function tolerances() {
  const q = [];
  for (const [id, name] of [['tolerance', 'tolerance_um'], ['location-tolerance', 'location_tolerance_um'], ['angle-tolerance', 'angle_tolerance_arcsec']])
    if ($(id).value) q.push(name + '=' + encodeURIComponent($(id).value));
  return q.length ? '?' + q.join('&') : '';
}

function verdict(pass) { return pass === null || pass === undefined ? '–' : pass ? 'PASS' : 'FAIL'; }

async function loadSession(id) {
  $('session-title').textContent = 'Session ' + id;
  const tol = $('tolerance').value;
  let s, rep;
  try {
    [s, rep] = await Promise.all([api('/api/sessions/' + id),
      api('/api/sessions/' + id + '/report.json' + tolerances())]);
  } catch (e) {
    $('session-title').textContent = 'Session ' + id + ': ' + e.message;
    return;
  }
  const m = s.session;
  $('session-title').textContent = 'Session ' + m.id + ' — ' + m.procedure + ', ' + m.state;
  $('report-pdf').href = withToken('/api/sessions/' + m.id + '/report.pdf' + (tol ? '?tolerance_um=' + encodeURIComponent(tol) : ''));
  $('session-title').dataset.session = m.id;
  $('export-json').href = withToken('/api/sessions/' + m.id + '/export?format=json');
  $('export-readings').href = withToken('/api/sessions/' + m.id + '/export?format=readings');
  $('export-trace').href = withToken('/api/sessions/' + m.id + '/export?format=trace');
  $('export-trace').hidden = m.procedure !== 'circular';
  $('export-readings').hidden = m.procedure === 'circular';
  $('resume').hidden = !m.resumable;
  $('resume-note').textContent = m.resumable ? 'Stopped: ' + (stateReason(m) || m.state) + '. ' +
    (m.procedure === 'circular' ? 'The program runs again for the runs it lacks.' : 'It goes on from the points it has.') : '';
  $('resume-go').onclick = async () => {
    try {
      await api('/api/procedure', { procedure: m.procedure === 'circular' ? 'circular' : 'ssm', resume: String(m.id), device: $('resume-device').value.trim() });
      location.hash = '#/';
    } catch (e) { $('resume-error').hidden = false; $('resume-error').textContent = e.message; }
  };
  const h = rep.header, t = h.temperatures_C || {};
  const inst = h.instrument ? h.instrument.model + ' ' + h.instrument.serial + ', firmware ' + h.instrument.firmware : null;
  kv($('conditions'), [['machine', machineName(m)], ['instrument', inst], ['operator', m.operator], ['started', m.started_at],
    ['ended', m.ended_at], ['state', m.state + (stateReason(m) ? ' (' + stateReason(m) + ')' : '')], ['notes', m.notes],
    ['bar temperature', t.bar ? fmt(t.bar.min, 2) + '–' + fmt(t.bar.max, 2) + ' °C' : null],
    ['air temperature', t.air ? fmt(t.air.min, 2) + '–' + fmt(t.air.max, 2) + ' °C' : null]]);
  const c = rep.circular;
  $('circular-results').hidden = !c;
  if (c) {
    const rows = c.runs.map((r) => ['G ' + r.direction, fmt(r.circularity_um, 2) + ' µm' + (r.pass === null ? '' : r.pass ? '  PASS' : '  FAIL')]);
    rows.push(['G(b) both directions', fmt(c.bidirectional_circularity_um, 2) + ' µm']);
    if (c.hysteresis_um !== null && c.hysteresis_um !== undefined) rows.push(['H hysteresis', fmt(c.hysteresis_um, 2) + ' µm']);
    rows.push(['tolerance', c.tolerance ? fmt(c.tolerance.circularity_um, 1) + ' µm (' + c.tolerance.source + ')' : 'none set']);
    rows.push(['plane, radius, feed', c.conditions.plane + ', ' + c.conditions.radius_mm + ' mm, ' + c.conditions.feed_mm_min + ' mm/min']);
    kv($('circular-figures'), rows);
    polar(c);
    $('diagnostics').tBodies[0].replaceChildren(...c.diagnostics.map((d) => {
      const tr = el('tr');
      [d.rank || '', d.name, fmt(d.value, 3) + ' ' + unit(d.unit), fmt(d.value_std, 3), d.share_percent ? fmt(d.share_percent, 1) + ' %' : '', d.action || ''].forEach((v) => tr.append(el('td', v)));
      return tr;
    }));
  }
  const ssm = rep.locations && rep.locations.length;
  $('ssm-results').hidden = !ssm;
  if (ssm) {
    $('locations').tBodies[0].replaceChildren(...rep.locations.map((l) => {
      const tr = el('tr');
      [l.label, l.dV_um.map((v) => fmt(v, 2)).join(', '), fmt(l.magnitude_um, 2), verdict(l.pass)].forEach((v) => tr.append(el('td', v)));
      tr.lastChild.className = l.pass === true ? 'ok' : l.pass === false ? 'error' : '';
      return tr;
    }));
    $('orientation').tBodies[0].replaceChildren(...rep.orientation.map((o) => {
      const tr = el('tr');
      [o.angle.replace('d_alpha', 'Δα').replace('d_beta', 'Δβ').replace('d_gamma', 'Δγ'), o.axis, fmt(o.exact_arcsec, 2),
        fmt(o.exact_arcsec_std, 3), verdict(o.pass)].forEach((v) => tr.append(el('td', v)));
      tr.lastChild.className = o.pass === true ? 'ok' : o.pass === false ? 'error' : '';
      return tr;
    }));
  }
  const gaps = s.sample_gaps || [];
  $('gaps').textContent = gaps.length ? gaps.length + ' gaps, ' + fmt(gaps.reduce((a, g) => a + (g.duration_s || 0), 0), 3) + ' s in all' : 'none';
  $('session-log').replaceChildren(...(rep.procedure || []).map((p) => el('li', p.at.replace('T', ' ').slice(0, 23) + '  ' + p.step + ': ' + (p.detail || ''))));
}
['tolerance', 'location-tolerance', 'angle-tolerance'].forEach((id) => { $(id).onchange = () => { const r = route(); if (r.id) loadSession(r.id); }; });

// ---- routes -----------------------------------------------------------------------------------------

function route() {
  const h = location.hash || '#/';
  const m = h.match(/^#\/session\/([0-9A-Za-z-]+)$/);
  if (m) return { view: 'session', id: m[1] };
  return { view: h === '#/sessions' ? 'sessions' : 'procedure' };
}

function show() {
  const r = route();
  $('view-procedure').hidden = r.view !== 'procedure';
  $('view-sessions').hidden = r.view !== 'sessions';
  $('view-session').hidden = r.view !== 'session';
  $('nav-procedure').className = r.view === 'procedure' ? 'active' : '';
  $('nav-sessions').className = r.view !== 'procedure' ? 'active' : '';
  if (r.view === 'sessions') loadSessions();
  if (r.view === 'session') loadSession(r.id);
}
window.addEventListener('hashchange', show);
show();
connect();
api('/api/procedure').then((s) => { if (!state) { state = s; stateAt = Date.now(); render(); } }).catch(() => {});
