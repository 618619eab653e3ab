// The web view of the finger: one console (docs/console.md) over two sources, the
// firmware's application compiled to WebAssembly (a simulated board, finger-wasm) or a real
// board over Web Serial; a drawing of the posture from `status` / `shape` (the same solve as
// `solve`), the controls, the limits and the board's refusals, the tip stiffness across a
// pose's feasible tension interval (or, before any pose, across the tension at the present
// voltages), the host's f64 model as an overlay, and a strip chart of `status` over time.
// The drawing is in mm, x along the straight finger, the flexor (cable) side up as in the
// scene figures: the world group is flipped (SVG's y grows downward).
'use strict';

// ------------------------------------------------------------------ console replies

/** A reply line read by the console protocol crate (finger-wasm's `reply_parse`, whichever
 * board answers): {final: 'ok' | 'err' | null, kv: {a: '1', b: '2,3'} of an `ok` line, code,
 * message of an `err` line}. */
function parseReply(line) {
  const e = state.wasm;
  const bytes = new TextEncoder().encode(line).subarray(0, e.io_cap());
  new Uint8Array(e.memory.buffer, e.io_buf(), bytes.length).set(bytes);
  const kind = e.reply_parse(bytes.length);
  const text = new TextDecoder().decode(new Uint8Array(e.memory.buffer, e.parsed_ptr(), e.parsed_len()).slice());
  const r = { final: [null, 'ok', 'err'][kind], kv: {}, code: '', message: '' };
  if (kind === 1) {
    for (const l of text.split('\n')) {
      const i = l.indexOf('=');
      if (i > 0) r.kv[l.slice(0, i)] = l.slice(i + 1);
    }
  } else if (kind === 2) {
    const i = text.indexOf('\n');
    r.code = text.slice(0, i);
    r.message = text.slice(i + 1);
  }
  return r;
}
const nums = (s) => (s || '').split(',').map(Number);
/** `x,y,deg,x,y,deg,...` -> [{x, y, th (rad)}] */
function poses(s) {
  const v = nums(s), out = [];
  for (let i = 0; i + 2 < v.length; i += 3) out.push({ x: v[i], y: v[i + 1], th: v[i + 2] * Math.PI / 180 });
  return out;
}

// ------------------------------------------------------------------ the two sources

/** The simulated board: finger-wasm's exports (web/finger-wasm/src/lib.rs). */
class WasmBoard {
  constructor(exports) {
    this.e = exports;
    this.onText = () => {};
    this.enc = new TextEncoder();
    this.dec = new TextDecoder();
    this.name = 'simulated board (WebAssembly)';
  }
  bytesIn(bytes) {
    const cap = this.e.io_cap();
    for (let i = 0; i < bytes.length; i += cap) {
      const chunk = bytes.subarray(i, i + cap);
      const p = this.e.io_buf(); // before touching memory.buffer: a call may grow it
      new Uint8Array(this.e.memory.buffer, p, chunk.length).set(chunk);
      this.e.fw_input(chunk.length);
    }
    this.flush();
  }
  write(text) { this.bytesIn(this.enc.encode(text)); }
  flush() {
    const p = this.e.out_ptr(), n = this.e.out_len();
    if (n === 0) return;
    const t = this.dec.decode(new Uint8Array(this.e.memory.buffer, p, n).slice());
    this.e.out_clear();
    this.onText(t);
  }
  advance(ms) { this.e.fw_tick(ms); this.flush(); }
  reset() { this.e.fw_reset(); }
}

/** A real board over Web Serial (115200 8N1). */
class SerialBoard {
  constructor(port) {
    this.port = port;
    this.onText = () => {};
    this.name = 'board over Web Serial';
  }
  async open() {
    await this.port.open({ baudRate: 115200 });
    this.writer = this.port.writable.getWriter();
    this.enc = new TextEncoder();
    (async () => {
      const dec = new TextDecoder();
      const reader = this.port.readable.getReader();
      for (;;) {
        const { value, done } = await reader.read();
        if (done) break;
        this.onText(dec.decode(value, { stream: true }));
      }
    })().catch((e) => log('note', 'serial: ' + e));
  }
  write(text) { this.writer.write(this.enc.encode(text)); }
  advance() {}
}

/** One console: commands in order, each resolved by its final line (`ok ...` / `err ...`).
 * `stop` jumps the queue: sent at once, the commands not yet sent are dropped. */
class Console {
  constructor(board) {
    this.board = board;
    this.buf = '';
    this.sent = []; // commands written, waiting for their final line
    this.queue = []; // not yet written
    board.onText = (t) => this.receive(t);
  }
  command(line, quiet = false) {
    return new Promise((resolve, reject) => {
      this.queue.push({ line, quiet, resolve, reject, lines: [] });
      this.pump();
    });
  }
  stop() {
    for (const c of this.queue) c.reject(new Error('dropped by stop'));
    this.queue = [];
    return new Promise((resolve, reject) => this.send({ line: 'stop', quiet: false, resolve, reject, lines: [] }));
  }
  pump() {
    if (this.sent.length === 0 && this.queue.length > 0) this.send(this.queue.shift());
  }
  send(c) {
    this.sent.push(c);
    if (!c.quiet) log('tx', '> ' + c.line);
    c.timer = setTimeout(() => this.timeout(c), 8000);
    this.board.write(c.line + '\n');
  }
  timeout(c) {
    const i = this.sent.indexOf(c);
    if (i >= 0) this.sent.splice(i, 1);
    c.reject(new Error('no reply to ' + c.line));
    this.pump();
  }
  receive(text) {
    this.buf += text;
    let i;
    while ((i = this.buf.search(/\r?\n|\r/)) >= 0) {
      const line = this.buf.slice(0, i);
      this.buf = this.buf.slice(i + (this.buf[i] === '\r' && this.buf[i + 1] === '\n' ? 2 : 1));
      if (line.trim() !== '') this.line(line.trim());
    }
  }
  line(l) {
    const c0 = this.sent[0];
    if (l.startsWith('#') || !c0) { log('note', l); return; }
    const r = parseReply(l);
    if (r.final) {
      // `ok stopped` answers the stop wherever it comes, ahead of the lines sent before the
      // stop; every other final line answers the oldest other line (docs/console.md "Lines")
      const isStop = (x) => /^\s*stop\b/i.test(x.line);
      const i = l === 'ok stopped' ? this.sent.findIndex(isStop) : this.sent.findIndex((x) => !isStop(x));
      if (i < 0) { log('note', l); return; }
      const c = this.sent.splice(i, 1)[0];
      clearTimeout(c.timer);
      const err = r.final === 'err';
      if (c.quiet && err) log('tx', '> ' + c.line); // a refusal is always logged
      if (!c.quiet || err) log(err ? 'err' : 'rx', l);
      c.resolve({ ok: !err, line: l, kv: r.kv, lines: c.lines });
      this.pump();
    } else {
      c0.lines.push(l);
      if (!c0.quiet) log('rx', l);
    }
  }
}

// ------------------------------------------------------------------ page state

const $ = (id) => document.getElementById(id);
const state = {
  con: null, wasm: null, board: null, armed: false, hasShape: true,
  params: { l: 27, b: 10, t_min: 1.5, a: 5, e: 5, layers: 4, z0: 0.5 },
  strip: [], stripT0: null,
  limits: {}, vmax: 10000, drawn: null, host: null, plot: null, busyPreview: false, pendingPreview: false,
};
window.finger = state; // for the tests and the curious

function log(kind, text) {
  const el = $('log');
  if (!el) return;
  const d = document.createElement('div');
  d.className = kind;
  d.textContent = text;
  el.appendChild(d);
  while (el.childNodes.length > 400) el.removeChild(el.firstChild);
  el.scrollTop = el.scrollHeight;
}

/** Show the board's answer: an `err` line as the board wrote it. */
function showReply(line, r) {
  const el = $('refusal');
  el.className = r.ok ? 'mono' : 'mono err';
  el.textContent = line + '  ->  ' + r.line;
  return r;
}

/** One command; quiet ones (polls, previews) stay out of the console log unless refused. */
const cmd = (line, quiet = true) => state.con.command(line, quiet);

// ------------------------------------------------------------------ drawing

const NS = 'http://www.w3.org/2000/svg';
function el(tag, attrs, parent) {
  const e = document.createElementNS(NS, tag);
  for (const k in attrs) e.setAttribute(k, attrs[k]);
  if (parent) parent.appendChild(e);
  return e;
}
const pt = (p, px, py) => [p.x + Math.cos(p.th) * px - Math.sin(p.th) * py, p.y + Math.sin(p.th) * px + Math.cos(p.th) * py];
const f3 = (v) => v.toFixed(3);

/** A curve from pose a to pose b (the hinge), offset by `off` along each end's normal. */
function hingePath(a, b, off) {
  const p0 = pt(a, 0, off), p1 = pt(b, 0, off);
  const len = Math.hypot(p1[0] - p0[0], p1[1] - p0[1]) / 3;
  const c0 = [p0[0] + Math.cos(a.th) * len, p0[1] + Math.sin(a.th) * len];
  const c1 = [p1[0] - Math.cos(b.th) * len, p1[1] - Math.sin(b.th) * len];
  return `M${f3(p0[0])},${f3(p0[1])} C${f3(c0[0])},${f3(c0[1])} ${f3(c1[0])},${f3(c1[1])} ${f3(p1[0])},${f3(p1[1])}`;
}

/** Draw a `shape` answer (nodes, hinge ends, stack thicknesses) and the volts on the stacks. */
function drawShape(g, s, volts, style) {
  g.innerHTML = '';
  const P = state.params, n = s.hinges.length;
  if (style === 'host') {
    const line = [];
    for (let k = 0; k < n; k++) line.push(s.nodes[k], s.hinges[k]);
    line.push(s.nodes[n]);
    el('polyline', { points: line.map((p) => f3(p.x) + ',' + f3(p.y)).join(' '), class: 'host-line', fill: 'none', stroke: '#0a0', 'stroke-width': 0.7, 'stroke-dasharray': '2 1.2' }, g);
    s.nodes.forEach((p, k) => el('circle', { cx: f3(p.x), cy: f3(p.y), r: 0.9, fill: 'none', stroke: '#0a0', 'stroke-width': 0.4, id: 'host-node-' + k }, g));
    g.dataset.tip = f3(s.nodes[n].x) + ',' + f3(s.nodes[n].y);
    return;
  }
  for (let k = 0; k < n; k++) {
    const a = s.nodes[k], h = s.hinges[k], b = s.nodes[k + 1];
    // link k: a bar of thickness b from the hinge's end to node k
    el('line', { x1: f3(h.x), y1: f3(h.y), x2: f3(b.x), y2: f3(b.y), stroke: '#8aa4c8', 'stroke-width': P.b, opacity: 0.85, class: 'link' }, g);
    // DE stack on the extensor (-y) side, centroid at t_min/2 + t/2
    const t = s.thick[k] || 0;
    if (t > 0 && P.layers > 0) {
      const frac = Math.min(1, (volts[k] || 0) / state.vmax);
      const col = `rgb(${Math.round(238 - 40 * frac)},${Math.round(170 - 120 * frac)},${Math.round(60 - 40 * frac)})`;
      el('path', { d: hingePath(a, h, -(P.t_min / 2 + t / 2)), stroke: col, 'stroke-width': t, fill: 'none', class: 'stack', 'data-thick': t }, g);
      // the 33 % limit: the stack's outer face may never come closer than 2/3 of its rest thickness
      const tLim = (2 / 3) * P.layers * P.z0;
      el('path', { d: hingePath(a, h, -(P.t_min / 2 + tLim)), stroke: '#d00', 'stroke-width': 0.3, 'stroke-dasharray': '1 0.6', fill: 'none', class: 'limit', 'data-joint': k + 1, 'data-limit-mm': tLim.toFixed(4) }, g);
    }
    el('path', { d: hingePath(a, h, 0), stroke: '#345', 'stroke-width': P.t_min, fill: 'none', class: 'hinge' }, g);
  }
  // the cable: base hole, then each link's proximal and distal holes (y = +e), anchored at the tip
  const holes = [pt(s.nodes[0], 0, P.e)];
  for (let k = 0; k < n; k++) holes.push(pt(s.hinges[k], 0, P.e), pt(s.nodes[k + 1], 0, P.e));
  el('polyline', { points: holes.map((q) => f3(q[0]) + ',' + f3(q[1])).join(' '), fill: 'none', stroke: '#c22', 'stroke-width': 0.5, class: 'cable' }, g);
  s.nodes.forEach((p, k) => el('circle', { cx: f3(p.x), cy: f3(p.y), r: 1.1, fill: '#123', id: 'node-' + k }, g));
  g.dataset.tip = f3(s.nodes[n].x) + ',' + f3(s.nodes[n].y);
  g.dataset.nodes = s.nodes.map((p) => f3(p.x) + ',' + f3(p.y)).join(';');
}

/** The drawing's view: the straight finger's box (clamp, body, scale bar), grown to hold the
 * posture with a small margin, so that the finger fills the pane at every posture. */
function fitView(s) {
  const xs = s.nodes.map((p) => p.x), ys = s.nodes.map((p) => p.y), m = 9;
  const x0 = Math.min(-16, Math.min(...xs) - m), x1 = Math.max(92, Math.max(...xs) + m);
  const y0 = Math.min(-24, Math.min(...ys) - m), y1 = Math.max(14, Math.max(...ys) + m);
  // the world group is flipped (flexor side up): world y maps to SVG -y
  $('finger').setAttribute('viewBox', `${x0.toFixed(1)} ${(-y1).toFixed(1)} ${(x1 - x0).toFixed(1)} ${(y1 - y0).toFixed(1)}`);
  drawScaleBar(x0, -y0);
  state.view = { x1, y0 };
  drawGravity();
}

/** Gravity's direction (`grav_dir`, degrees from the straight finger's axis +x toward the
 * cable side +y) as an arrow `g` at the drawing's bottom right; none when `grav` is 0. */
function drawGravity() {
  const g = $('gravity');
  if (!g || !state.view) return;
  g.innerHTML = '';
  const grav = Number(state.params.grav || 0), dir = Number(state.params.grav_dir || 0);
  // bottom right: the cable flexes the finger upward (toward +y), so the corner stays free
  const cx = state.view.x1 - 15, cy = -state.view.y0 - 14, L = 6;
  // base frame to SVG: x right, world y up (the world group is flipped)
  const ux = Math.cos(dir * Math.PI / 180), uy = -Math.sin(dir * Math.PI / 180);
  g.dataset.grav = grav;
  g.dataset.dir = dir;
  if (!(grav > 0)) {
    el('text', { x: cx, y: cy, 'text-anchor': 'middle', 'font-size': 2.8, fill: '#666', class: 'no-grav' }, g).textContent = 'no gravity';
    return;
  }
  const x0 = cx - ux * L, y0 = cy - uy * L, x1 = cx + ux * L, y1 = cy + uy * L;
  el('line', { x1: f3(x0), y1: f3(y0), x2: f3(x1), y2: f3(y1), stroke: '#606', 'stroke-width': 0.7, class: 'arrow' }, g);
  // the head: two strokes back from the tip at ±25°
  const h = 2.2, a = Math.atan2(uy, ux);
  for (const s of [1, -1]) {
    const b = a + Math.PI + s * 0.44;
    el('line', { x1: f3(x1), y1: f3(y1), x2: f3(x1 + h * Math.cos(b)), y2: f3(y1 + h * Math.sin(b)), stroke: '#606', 'stroke-width': 0.7, class: 'head' }, g);
  }
  el('text', { x: f3(cx), y: f3(cy + L + 4.5), 'text-anchor': 'middle', 'font-size': 3.0, fill: '#606', class: 'label' }, g).textContent = `g ${grav} m/s², ${dir}°`;
}

/** A 10 mm scale bar at the drawing's bottom left (SVG coordinates: x right, y down). */
function drawScaleBar(left, bottom) {
  const g = $('scale-bar');
  g.innerHTML = '';
  const L = 10, x = left + 4, y = bottom - 5;
  el('line', { x1: x, y1: y, x2: x + L, y2: y, stroke: '#000', 'stroke-width': 0.6, class: 'bar', 'data-mm': L }, g);
  for (const xe of [x, x + L]) el('line', { x1: xe, y1: y - 1.2, x2: xe, y2: y + 1.2, stroke: '#000', 'stroke-width': 0.4 }, g);
  el('text', { x: x + L / 2, y: y - 1.8, 'text-anchor': 'middle', 'font-size': 3.2 }, g).textContent = `${L} mm`;
  el('text', { x: x + L + 3, y: y + 1.2, 'font-size': 2.6, fill: '#666' }, g).textContent = 'flexor (cable) side up';
}

function shapeOf(kv) {
  return { nodes: poses(kv.nodes), hinges: poses(kv.hinges), thick: nums(kv.thick) };
}

/** Host f64 model at (P, V): its shape, or null. */
function hostShape(p, v) {
  if (!state.wasm) return null;
  const e = state.wasm;
  e.out_clear();
  e.host_shape(p, v[0], v[1], v[2]);
  const t = new TextDecoder().decode(new Uint8Array(e.memory.buffer, e.out_ptr(), e.out_len()).slice()).trim();
  e.out_clear();
  const r = parseReply(t);
  if (r.final !== 'ok') return { err: t };
  return { ...shapeOf(r.kv), kv: r.kv };
}

function hostPose(d, p) {
  const e = state.wasm;
  e.out_clear();
  e.host_pose(d[0], d[1], d[2], p == null ? NaN : p);
  const t = new TextDecoder().decode(new Uint8Array(e.memory.buffer, e.out_ptr(), e.out_len()).slice()).trim();
  e.out_clear();
  const r = parseReply(t);
  return { ok: r.final === 'ok', line: t, kv: r.kv };
}

/** Draw the board's posture at (P, V): `shape` (the same solve as `solve`), with `solve`'s
 * figures in the readout, and the host f64 model's over it. */
async function drawAt(p, v, mode) {
  const args = `${p} ${v[0]} ${v[1]} ${v[2]}`;
  const sol = await cmd('solve ' + args);
  let shape = null;
  if (state.hasShape) {
    const r = await cmd('shape ' + args);
    if (r.ok) shape = shapeOf(r.kv);
    else if (/^err unknown/.test(r.line)) state.hasShape = false;
  }
  const host = hostShape(p, v);
  const g = $('board-shape'), gh = $('host-shape');
  if (!sol.ok) {
    showReply('solve ' + args, sol);
    $('readout').textContent = sol.line;
    return sol;
  }
  if (!shape && host && !host.err) shape = host; // a board without `shape`: the host's geometry
  if (shape) drawShape(g, shape, v, 'board');
  if (host && !host.err) drawShape(gh, host, v, 'host'); else gh.innerHTML = '';
  if (shape) fitView(shape);
  state.drawn = { p, v, solve: sol.kv, shape, host };
  g.dataset.p = p;
  g.dataset.v = v.join(',');
  $('view-mode').textContent = mode + (state.hasShape ? '' : ' (board has no shape: host geometry, board tip from solve)');
  let txt = `${mode}: P = ${p} N, V = ${v.join(', ')} V\n` + `board:  ${readable(sol.kv)}`;
  if (host && !host.err) {
    const tb = nums(sol.kv.tip), th = host.nodes[host.nodes.length - 1];
    txt += `\nhost f64: joints ${nums(host.kv.joints).map((x) => x.toFixed(3)).join(', ')} deg; ${stiffText(host.kv.stiffness)}` +
      `\n  tip board - host: ${Math.hypot(tb[0] - th.x, tb[1] - th.y).toExponential(2)} mm`;
  } else if (host) txt += '\nhost f64: ' + host.err;
  $('readout').textContent = txt;
  return sol;
}

/** Tip stiffness `kxx,kyy,kθθ` with its units. */
function stiffText(s) {
  const k = nums(s);
  return `tip stiffness k_xx ${k[0].toPrecision(4)} N/mm, k_yy ${k[1].toPrecision(4)} N/mm, k_θθ ${k[2].toPrecision(4)} N·mm/rad`;
}

/** A `solve` reply in words and units (docs/console.md). */
function readable(kv) {
  const tip = nums(kv.tip);
  return `joints ${nums(kv.joints).join(', ')} deg; tip x ${tip[0]} mm, y ${tip[1]} mm, ${tip[2]} deg; ` +
    `cable ${kv.cable} mm; stacks ${nums(kv.thick).join(', ')} mm\n        ${stiffText(kv.stiffness)}; ` +
    `iters ${kv.iters}${kv.iters === '0' ? ' (branch table)' : ''}`;
}

// ------------------------------------------------------------------ axes

/** Tick values for [lo, hi]: about n steps of 1, 2 or 5 times a power of ten. */
function niceTicks(lo, hi, n = 4) {
  const span = hi - lo;
  if (!(span > 0)) return [lo];
  const raw = span / n, p = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 5, 10].map((m) => m * p).find((x) => x >= raw);
  const out = [];
  for (let t = Math.ceil(lo / step - 1e-9) * step; t <= hi + step * 1e-9; t += step) out.push(+t.toPrecision(12));
  return out;
}

/** A tick's label with as many decimals as its step needs. */
function tickLabel(t, ticks) {
  const step = ticks.length > 1 ? Math.abs(ticks[1] - ticks[0]) : Math.abs(t) || 1;
  const dec = Math.max(0, Math.min(6, -Math.floor(Math.log10(step) + 1e-9)));
  return t.toFixed(dec);
}

/** A padded axis range for values `vals`; a flat series gets `minSpan` around it. */
function axisRange(vals, minSpan) {
  let lo = vals.length ? Math.min(...vals) : 0, hi = vals.length ? Math.max(...vals) : minSpan;
  if (hi - lo < minSpan) { const c = (hi + lo) / 2; lo = c - minSpan / 2; hi = c + minSpan / 2; }
  const pad = (hi - lo) * 0.08;
  return [lo - pad, hi + pad];
}

// ------------------------------------------------------------------ strip chart

const STRIP_MAX = 4800; // 20 min at 4 samples a second
const STRIP_WINDOW_S = 60;

/** One `status` sample into the strip chart. */
function stripAdd(kv) {
  const now = performance.now();
  if (state.stripT0 == null) state.stripT0 = now;
  state.strip.push({
    t: (now - state.stripT0) / 1000, force: Number(kv.force), volts: nums(kv.volts), thick: nums(kv.thick), joints: nums(kv.joints),
    // the read-back (a board without one: none), NaN until measured
    vmeas: nums(kv.vmeas), imeas: nums(kv.imeas), thickMeas: nums(kv.thick_meas),
  });
  if (state.strip.length > STRIP_MAX) state.strip.shift();
  drawStrip();
}

/** The samples as CSV, one row a `status`, units in the header. */
function stripCsv() {
  const head = 't_s,tension_N,v1_V,v2_V,v3_V,thick1_mm,thick2_mm,thick3_mm,joint1_deg,joint2_deg,joint3_deg'
    + ',vmeas1_V,vmeas2_V,vmeas3_V,imeas1_uA,imeas2_uA,imeas3_uA,thick_meas1_mm,thick_meas2_mm,thick_meas3_mm';
  const three = (a) => [0, 1, 2].map((k) => (Number.isFinite(a[k]) ? a[k] : ''));
  return [head, ...state.strip.map((r) => [r.t.toFixed(3), r.force, ...r.volts, ...r.thick, ...r.joints, ...three(r.vmeas), ...three(r.imeas), ...three(r.thickMeas)].join(','))].join('\n') + '\n';
}
state.stripCsv = stripCsv;

function drawStrip() {
  const svg = $('strip');
  if (!svg) return;
  svg.innerHTML = '';
  // one colour per channel (the tension, one series, in black); a channel's own dash and
  // width, so that channels at the same value stay visible on top of each other. A row's
  // `meas`: the read-back beside the command or the model (thin, faded; class `-meas`)
  const W = 520, L = 64, R = 90, T = 6, H = 380, rows = [
    { name: 'tension', unit: 'N', get: (r) => [r.force], span: 0.1 },
    { name: 'voltage', unit: 'V', get: (r) => r.volts, meas: (r) => r.vmeas || [], span: 100 },
    { name: 'current', unit: 'µA', get: (r) => r.imeas || [], span: 0.2 },
    { name: 'stack', unit: 'mm', get: (r) => r.thick, meas: (r) => r.thickMeas || [], span: 0.01 },
    { name: 'joints', unit: 'deg', get: (r) => r.joints, span: 0.5 },
  ];
  const cols = ['#06c', '#c60', '#393'], dash = ['', '7 4', '2 3'], widths = [3, 2, 1.3], rowH = (H - T - 18) / rows.length;
  const data = state.strip;
  $('strip-count').textContent = `${data.length} samples`;
  const tEnd = data.length ? data[data.length - 1].t : 0, tStart = Math.max(0, tEnd - STRIP_WINDOW_S);
  const shown = data.filter((r) => r.t >= tStart);
  const X = (t) => L + (t - tStart) / Math.max(1e-9, Math.max(tEnd - tStart, 1)) * (W - L - R);
  rows.forEach((row, i) => {
    const y0 = T + i * rowH, h = rowH - 10;
    el('rect', { x: L, y: y0, width: W - L - R, height: h, fill: 'none', stroke: '#ccc' }, svg);
    const vals = shown.flatMap((r) => [...row.get(r), ...(row.meas ? row.meas(r) : [])]).filter(Number.isFinite);
    const [lo, hi] = axisRange(vals, row.span);
    const Y = (v) => y0 + h - (v - lo) / (hi - lo) * h;
    const ticks = niceTicks(lo, hi, 3);
    for (const t of ticks) {
      el('line', { x1: L, x2: W - R, y1: Y(t), y2: Y(t), stroke: '#eee' }, svg);
      el('text', { x: L - 4, y: Y(t) + 3, 'text-anchor': 'end', 'font-size': 10, class: 'tick' }, svg).textContent = tickLabel(t, ticks);
    }
    el('text', { x: W - R + 6, y: y0 + 12, 'font-size': 11 }, svg).textContent = `${row.name} (${row.unit})`;
    const first = shown[0] || { force: 0, volts: [], thick: [], joints: [], vmeas: [], imeas: [], thickMeas: [] };
    // a series' points where it is measured (NaN before the read-back has a value)
    const points = (get, c) => shown.filter((r) => Number.isFinite(get(r)[c])).map((r) => `${X(r.t).toFixed(1)},${Y(get(r)[c]).toFixed(1)}`).join(' ');
    const n = row.get(first).length;
    for (let c = 0; c < n; c++) {
      const col = n > 1 ? cols[c % 3] : '#222';
      el('polyline', { points: points(row.get, c), fill: 'none', stroke: col, 'stroke-width': n > 1 ? widths[c % 3] : 1.6, 'stroke-dasharray': n > 1 ? dash[c % 3] : '', class: `strip-${row.name}`, 'data-channel': c + 1 }, svg);
      if (n > 1) el('text', { x: W - R + 6 + 24 * c, y: y0 + 26, 'font-size': 10, fill: cols[c % 3] }, svg).textContent = String(c + 1);
    }
    const m = row.meas ? row.meas(first).length : 0;
    for (let c = 0; c < m; c++) {
      el('polyline', { points: points(row.meas, c), fill: 'none', stroke: cols[c % 3], 'stroke-width': 1, 'stroke-opacity': 0.6, 'stroke-dasharray': '1 2', class: `strip-${row.name}-meas`, 'data-channel': c + 1 }, svg);
    }
    if (m > 0) el('text', { x: W - R + 6, y: y0 + 40, 'font-size': 9, fill: '#666' }, svg).textContent = row.name === 'voltage' ? 'dotted: measured' : 'dotted: sensed';
  });
  el('text', { x: (L + W - R) / 2, y: H - 4, 'text-anchor': 'middle', 'font-size': 11 }, svg).textContent =
    `time (s), the last ${STRIP_WINDOW_S} s: ${tStart.toFixed(1)} .. ${tEnd.toFixed(1)}`;
}

function exportStrip() {
  const a = document.createElement('a');
  a.href = URL.createObjectURL(new Blob([stripCsv()], { type: 'text/csv' }));
  a.download = 'finger-status.csv';
  a.click();
  setTimeout(() => URL.revokeObjectURL(a.href), 1000);
}

// ------------------------------------------------------------------ controls

const sliders = () => ({ p: Number($('force').value), v: [1, 2, 3].map((k) => Number($('v' + k).value)) });
function setSlider(id, x) { $(id).value = x; $(id + '-out').textContent = x; }
function setSliders(p, v) {
  if (p != null) { $('force').value = p; $('force-out').textContent = p; }
  if (v) v.forEach((x, k) => { $('v' + (k + 1)).value = x; $('v' + (k + 1) + '-out').textContent = x; });
}

/** Disarmed: preview the sliders' setpoints (latest wins while one is being drawn). */
async function preview() {
  if (state.busyPreview) { state.pendingPreview = true; return; }
  state.busyPreview = true;
  try {
    do {
      state.pendingPreview = false;
      const s = sliders();
      await drawAt(s.p, s.v, 'preview (disarmed, solve)');
    } while (state.pendingPreview);
  } catch (e) { log('note', String(e)); }
  state.busyPreview = false;
  state.previewDone = (state.previewDone || 0) + 1;
}

async function onSlider(id) {
  const x = $(id).value;
  $(id + '-out').textContent = x;
  if (!state.armed) return preview();
  // armed: the board moves (and refuses what it must)
  const line = id === 'force' ? `force ${x}` : `volt ${id.slice(1)} ${x}`;
  const r = showReply(line, await cmd(line, false));
  await refreshLimits();
  if (!r.ok) { state.held = null; await poll(true); } // back to what the board holds
}

async function refreshLimits() {
  const r = await cmd('limits');
  if (!r.ok) return;
  state.limits = r.kv;
  const vmax = nums(r.kv.vmax)[0];
  if (vmax > 0) state.vmax = vmax;
  $('limits').textContent = Object.entries(r.kv).map(([k, v]) => `${k}=${v}`).join('\n');
  // sliders reach a little past the ceilings, so that the board's refusal can be seen
  const vm = nums(r.kv.vmax);
  for (const k of [1, 2, 3]) {
    $('v' + k).max = Math.ceil(state.vmax * 1.1 / 100) * 100;
    const ok = r.kv.vmax_ok ? nums(r.kv.vmax_ok)[k - 1] : vm[k - 1];
    $('v' + k + '-ceil').textContent = `(the board takes up to ${ok} V, below its ${vm[k - 1]} V ceiling; the last 10 % of the slider shows its refusal)`;
  }
  $('force-ceil').textContent = `(fmax ${r.kv.fmax} N at these setpoints)`;
  $('volt-scale-hi').textContent = `${state.vmax} V (ceiling)`;
  const fmax = Number(r.kv.fmax);
  if (fmax > 0 && !state.fmaxSet) { $('force').max = Math.ceil(fmax * 1.2); state.fmaxSet = true; }
}

/** The orientation control and the arrow follow the board's `grav`, `grav_dir`. */
function showOrientation() {
  const d = Number(state.params.grav_dir || 0), g = Number(state.params.grav || 0);
  if (state.held !== 'grav-dir') { $('grav-dir').value = d; $('grav-dir-out').textContent = d; }
  $('grav-state').textContent = g > 0 ? `(g ${g} m/s² at ${d}°)` : '(no gravity: param grav 0)';
  drawGravity();
}

/** Set the orientation at the board (`param grav_dir`, refused while armed), then redraw. */
async function setOrientation(d) {
  const line = `param grav_dir ${d}`;
  const r = showReply(line, await cmd(line, false));
  if (r.ok) { await readParams(); await refreshLimits(); }
  showOrientation();
  if (r.ok && !state.armed) await preview();
  return r;
}

async function readParams() {
  const r = await cmd('param');
  if (!r.ok) return;
  if (state.wasm) state.wasm.host_reset();
  for (const l of r.lines) {
    const m = /^(\w+)=(\S+)/.exec(l);
    if (!m) continue;
    const v = Number(m[2]);
    state.params[m[1]] = v;
    if (state.wasm) {
      const b = new TextEncoder().encode(m[1]);
      const p = state.wasm.io_buf();
      new Uint8Array(state.wasm.memory.buffer, p, b.length).set(b);
      state.wasm.host_param(b.length, v);
    }
  }
  showOrientation();
}

/** Armed: the board's state now (`status`) drawn live. */
async function poll(force = false) {
  if (!state.con || (state.polling && !force)) return;
  state.polling = true;
  try {
    const r = await cmd('status');
    if (!r.ok) return;
    const armed = r.kv.armed === '1';
    const fault = r.kv.fault && r.kv.fault !== 'none' ? r.kv.fault : '';
    $('armed-state').textContent = armed ? 'ARMED' : 'disarmed';
    $('armed-state').className = 'pill ' + (armed ? 'on' : 'off');
    $('fault-state').textContent = fault ? 'fault ' + fault : '';
    $('fault-state').className = 'pill' + (fault ? ' fault' : '');
    const was = state.armed;
    state.armed = armed;
    $('ctl-mode').textContent = armed ? '(armed: moves the board)' : '(disarmed: preview)';
    state.status = r.kv;
    stripAdd(r.kv);
    if (armed) {
      // the sliders follow the board's setpoints (tension, HV targets), except one held
      const tv = nums(r.kv.target || r.kv.volts);
      if (state.held !== 'force') setSlider('force', Number(r.kv.force));
      tv.forEach((x, k) => { if (state.held !== 'v' + (k + 1)) setSlider('v' + (k + 1), x); });
    }
    if (armed || (was && !armed)) {
      const v = nums(r.kv.volts), p = Number(r.kv.force);
      const key = p + '|' + v.join(',');
      if (key !== state.lastLive || force) {
        state.lastLive = key;
        await drawAt(p, v, armed ? 'live (armed, status)' : 'preview');
      }
    }
  } catch (e) { log('note', String(e)); } finally { state.polling = false; }
}

async function doPose() {
  const d = [1, 2, 3].map((k) => Number($('d' + k).value));
  const pArg = $('dp').value.trim();
  const line = `pose ${d.join(' ')}${pArg ? ' ' + pArg : ''}`;
  const r = showReply(line, await cmd(line, false));
  const out = $('pose-out');
  if (!r.ok) { out.textContent = r.line; await sweepPlot(); return r; }
  const [lo, hi] = nums(r.kv.range), volts = nums(r.kv.volts), p = Number(r.kv.force);
  setSliders(p, volts);
  // the ends of the feasible interval: the board's inverse there (model only while disarmed),
  // the host f64 model's while armed (an armed pose would move the board)
  const ends = [];
  const samples = [];
  const N = 9;
  const src = state.armed ? 'host f64 model (armed: board pose would move)' : 'board (pose + solve, disarmed)';
  for (let i = 0; i < N; i++) {
    const t = lo + (hi - lo) * i / (N - 1);
    const s = await stiffnessAt(d, t);
    if (s) samples.push({ t, x: s.volts.reduce((a, b) => a + b, 0) / s.volts.length, k: s.k, host: s.host });
    if (i === 0 || i === N - 1) ends.push(s);
  }
  const fmt = (s) => s ? `kxx=${s.k[0].toPrecision(4)} kyy=${s.k[1].toPrecision(4)} ktt=${s.k[2].toPrecision(4)} (volts ${s.volts.map((x) => x.toFixed(0)).join(',')})` : '-';
  out.textContent = `force=${r.kv.force} N volts=${r.kv.volts} V\nfeasible tension ${lo} .. ${hi} N\n` +
    `tip stiffness at ${lo} N: ${fmt(ends[0])}\ntip stiffness at ${hi} N: ${fmt(ends[1])}\n(N/mm, N/mm, N·mm/rad)`;
  state.plot = { kind: 'pose', lo, hi, samples, src, d };
  drawPlot();
  if (!state.armed) await drawAt(p, volts, 'pose preview (disarmed, solve)');
  else await poll(true);
  return r;
}

/** Tip stiffness (kxx, kyy, kθθ) of pose d at tension t, from the board (disarmed) or the host. */
async function stiffnessAt(d, t) {
  let host = null;
  if (state.wasm) {
    const h = hostPose(d, t);
    if (h.ok) host = nums(h.kv.stiffness);
  }
  if (state.armed) return host ? { k: host, host, volts: nums(hostPose(d, t).kv.volts) } : null;
  const r = await cmd(`pose ${d.join(' ')} ${t}`);
  if (!r.ok) return null;
  const v = nums(r.kv.volts);
  const s = await cmd(`solve ${t} ${v.join(' ')}`);
  if (!s.ok) return null;
  return { k: nums(s.kv.stiffness), host, volts: v };
}

function drawPlot() {
  const svg = $('plot');
  svg.innerHTML = '';
  const P = state.plot;
  const W = 520, H = 260, L = 72, R = 110, T = 12, B = 36;
  if (!P || P.samples.length === 0) {
    el('text', { x: W / 2, y: H / 2, 'text-anchor': 'middle', fill: '#888' }, svg).textContent = 'pose a target to see its stiffness range';
    $('plot-src').textContent = '';
    return;
  }
  $('plot-src').textContent = P.kind === 'pose' ? `pose ${P.d.join(', ')} deg; from the ${P.src}` : P.src;
  // each stiffness relative to its value at the low end (linear): the interval is often
  // narrow, and the three differ by orders of magnitude
  const names = ['kxx', 'kyy', 'kθθ'], units = ['N/mm', 'N/mm', 'N·mm/rad'], cols = ['#06c', '#c60', '#393'];
  const base = P.samples[0].k;
  const rel = (s, c, k) => (k || s.k)[c] / base[c];
  const all = [];
  for (const s of P.samples) for (let c = 0; c < 3; c++) { all.push(rel(s, c)); if (s.host) all.push(rel(s, c, s.host)); }
  // in percent, on ticks of 1, 2 or 5
  const pct = all.map((r) => (r - 1) * 100);
  const [y0, y1] = axisRange(pct, 0.05);
  // x: the voltage (the pose's mean channel voltage across its interval; the sweep's channels)
  const xv = (s) => s.x;
  const xs = P.samples.map(xv), x0 = Math.min(...xs), x1 = Math.max(...xs), span = x1 - x0 || 1;
  const X = (x) => L + (x - x0) / span * (W - L - R), Y = (q) => T + (y1 - q) / (y1 - y0) * (H - T - B);
  el('rect', { x: L, y: T, width: W - L - R, height: H - T - B, fill: 'none', stroke: '#999' }, svg);
  const yt = niceTicks(y0, y1, 4);
  for (const q of yt) {
    el('line', { x1: L, x2: W - R, y1: Y(q), y2: Y(q), stroke: '#eee' }, svg);
    el('text', { x: L - 4, y: Y(q) + 4, 'text-anchor': 'end', 'font-size': 11, class: 'tick' }, svg).textContent = tickLabel(q, yt) + ' %';
  }
  const xt = niceTicks(x0, x1, 5);
  for (const x of xt) {
    el('text', { x: X(x), y: H - B + 14, 'text-anchor': 'middle', 'font-size': 11, class: 'xtick' }, svg).textContent = tickLabel(x, xt);
  }
  el('text', { x: (L + W - R) / 2, y: H - 6, 'text-anchor': 'middle', 'font-size': 11 }, svg).textContent =
    P.kind === 'pose' ? `mean channel voltage (V) across the feasible interval, P ${P.lo}..${P.hi} N` : `channel voltage (V), all three alike, at P = ${P.p} N`;
  el('text', { x: L + 6, y: T + 14, 'font-size': 10, fill: '#555' }, svg).textContent = P.kind === 'pose' ? 'k / k(softest end) - 1' : 'k / k(0 V) - 1';
  const last = P.samples[P.samples.length - 1].k;
  for (let c = 0; c < 3; c++) {
    const pts = P.samples.map((s) => `${X(xv(s)).toFixed(1)},${Y((rel(s, c) - 1) * 100).toFixed(1)}`).join(' ');
    el('polyline', { points: pts, fill: 'none', stroke: cols[c], 'stroke-width': 2.5, class: 'k' + c }, svg);
    P.samples.forEach((s) => el('circle', { cx: X(xv(s)), cy: Y((rel(s, c) - 1) * 100), r: 2.5, fill: cols[c] }, svg));
    el('text', { x: W - R + 6, y: T + 12 + 30 * c, fill: cols[c], 'font-size': 11 }, svg).textContent = `${names[c]} ${units[c]}`;
    el('text', { x: W - R + 6, y: T + 25 + 30 * c, fill: cols[c], 'font-size': 10 }, svg).textContent = `${base[c].toPrecision(4)} → ${last[c].toPrecision(4)}`;
  }
  // the host's f64 model on top: black dashes and open squares, visible where it coincides
  for (let c = 0; c < 3; c++) {
    const hs = P.samples.filter((s) => s.host);
    if (!hs.length) continue;
    el('polyline', { points: hs.map((s) => `${X(xv(s)).toFixed(1)},${Y((rel(s, c, s.host) - 1) * 100).toFixed(1)}`).join(' '), fill: 'none', stroke: '#000', 'stroke-dasharray': '3 3', 'stroke-width': 1, class: 'host-k' + c }, svg);
    hs.forEach((s) => el('rect', { x: X(xv(s)) - 2.5, y: Y((rel(s, c, s.host) - 1) * 100) - 2.5, width: 5, height: 5, fill: 'none', stroke: '#000', 'stroke-width': 0.8, class: 'host-mark' }, svg));
  }
  el('text', { x: W - R + 6, y: T + 104, fill: '#000', 'font-size': 10 }, svg).textContent = 'black dashes, □:';
  el('text', { x: W - R + 6, y: T + 116, fill: '#000', 'font-size': 10 }, svg).textContent = 'host f64 model';
}

/** Before any pose: the tip stiffness at the present tension (1 N when it is 0) with all three
 * channels from 0 V to just below the ceiling, from the board's `solve` (nothing moves): how
 * much the voltage changes the stiffness. */
async function sweepPlot() {
  const p0 = state.armed && state.status ? Number(state.status.force) : sliders().p;
  const p = p0 > 0 ? p0 : 1;
  const top = Math.floor(0.99 * (state.vmax || 0) / 100) * 100, N = 8, samples = [];
  for (let i = 0; i < N; i++) {
    const x = Math.round(top * i / (N - 1)), v = [x, x, x];
    const s = await cmd(`solve ${p} ${v.join(' ')}`);
    if (!s.ok) continue;
    const h = hostShape(p, v);
    samples.push({ t: p, x, k: nums(s.kv.stiffness), host: h && !h.err ? nums(h.kv.stiffness) : null });
  }
  state.plot = { kind: 'sweep', lo: p, hi: p, p, samples, src: `solve at P = ${p} N, every channel from 0 to ${top} V (no pose yet)` };
  drawPlot();
}

// ------------------------------------------------------------------ connect

async function connect(board) {
  if (state.con) for (const c of state.con.queue) c.reject(new Error('source changed'));
  state.board = board;
  state.con = new Console(board);
  state.hasShape = true;
  state.fmaxSet = false;
  $('source').textContent = board.name;
  log('note', '# connected: ' + board.name);
  await cmd('version', false);
  await readParams();
  await refreshLimits();
  await poll(true);
  if (!state.armed) await preview();
  await sweepPlot();
  state.ready = true;
}

async function loadWasm() {
  const b64 = window.FINGER_WASM_B64;
  const bin = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
  const { instance } = await WebAssembly.instantiate(bin, {});
  return instance.exports;
}

async function useSim() {
  state.ready = false;
  if (!state.wasm) state.wasm = await loadWasm();
  state.wasm.fw_reset();
  await connect(new WasmBoard(state.wasm));
}

async function useSerial() {
  if (!('serial' in navigator)) { showReply('serial', { ok: false, line: 'Web Serial is not available in this browser (Chromium has it)' }); return; }
  const port = await navigator.serial.requestPort();
  const b = new SerialBoard(port);
  // the replies are read by the wasm module's parser (the console protocol crate)
  if (!state.wasm) state.wasm = await loadWasm();
  await b.open();
  state.ready = false;
  await connect(b);
}

async function stop() {
  if (!state.con) return;
  const r = await state.con.stop();
  showReply('stop', r);
  setSliders(0, [0, 0, 0]);
  await poll(true);
}

function wire() {
  $('stop').addEventListener('click', () => stop().catch((e) => log('note', String(e))));
  document.addEventListener('keydown', (e) => { if (e.key === 'Escape') stop(); });
  $('arm').addEventListener('click', async () => { showReply('arm', await cmd('arm', false)); await refreshLimits(); await poll(true); });
  $('disarm').addEventListener('click', async () => { showReply('disarm', await cmd('disarm', false)); await poll(true); });
  for (const id of ['force', 'v1', 'v2', 'v3']) {
    $(id).addEventListener('input', () => { $(id + '-out').textContent = $(id).value; if (!state.armed) preview(); });
    $(id).addEventListener('change', () => onSlider(id).catch((e) => log('note', String(e))));
    $(id).addEventListener('pointerdown', () => { state.held = id; });
    $(id).addEventListener('pointerup', () => { state.held = null; });
    $(id).addEventListener('focus', () => { state.held = id; });
    $(id).addEventListener('blur', () => { state.held = null; });
  }
  $('pose').addEventListener('click', () => doPose().catch((e) => log('note', String(e))));
  $('grav-dir').addEventListener('input', () => { $('grav-dir-out').textContent = $('grav-dir').value; });
  $('grav-dir').addEventListener('change', () => setOrientation($('grav-dir').value).catch((e) => log('note', String(e))));
  for (const b of document.querySelectorAll('.grav-preset')) {
    b.addEventListener('click', () => setOrientation(b.dataset.dir).catch((e) => log('note', String(e))));
  }
  $('cmd-form').addEventListener('submit', async (e) => {
    e.preventDefault();
    const line = $('cmd').value.trim();
    if (!line) return;
    $('cmd').value = '';
    if (/^stop$/i.test(line)) return stop();
    const r = showReply(line, await cmd(line, false));
    if (/^(param|preset)\b/i.test(line) && r.ok) { await readParams(); await refreshLimits(); }
    await poll(true);
  });
  $('use-sim').addEventListener('click', () => useSim());
  $('strip-csv').addEventListener('click', exportStrip);
  $('use-serial').addEventListener('click', () => useSerial().catch((e) => log('note', String(e))));
  if (!('serial' in navigator)) $('use-serial').disabled = true;
  // time: the simulated board's control loop follows the page's clock; status every 250 ms
  let last = performance.now(), lastPoll = 0;
  setInterval(() => {
    const now = performance.now();
    const dt = Math.min(100, Math.max(0, Math.round(now - last)));
    last = now;
    if (state.board && dt > 0) state.board.advance(dt);
    if (state.ready && now - lastPoll > 250) { lastPoll = now; poll(); }
  }, 20);
  drawPlot();
  drawStrip();
}

wire();
useSim().catch((e) => { log('err', 'wasm: ' + e); showReply('load', { ok: false, line: 'err: ' + e }); });
