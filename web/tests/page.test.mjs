// The web view in headless Chromium (Debian's /usr/bin/chromium, driven by playwright-core;
// no browser download). Serves web/dist (built by web/build) from a loopback port.
// WEB_SHOTS=<dir> writes the screenshots there (`web/test --shots`: docs/).
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import http from 'node:http';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

const here = path.dirname(fileURLToPath(import.meta.url));
const dist = path.resolve(here, '..', 'dist');
const shots = process.env.WEB_SHOTS || fs.mkdtempSync(path.join(os.tmpdir(), 'web-shots-'));
const types = { '.html': 'text/html', '.js': 'text/javascript', '.css': 'text/css' };

let server, ctx, page, url, profile;
const pageErrors = [];

before(async () => {
  assert.ok(fs.existsSync(path.join(dist, 'index.html')), 'web/dist missing: run web/build');
  server = http.createServer((req, res) => {
    const f = path.join(dist, path.normalize(decodeURIComponent(req.url.split('?')[0])).replace(/^\/+$/, 'index.html'));
    if (!f.startsWith(dist) || !fs.existsSync(f) || fs.statSync(f).isDirectory()) { res.writeHead(404); res.end(); return; }
    res.writeHead(200, { 'content-type': types[path.extname(f)] || 'application/octet-stream' });
    fs.createReadStream(f).pipe(res);
  });
  await new Promise((r) => server.listen(0, '127.0.0.1', r));
  url = `http://127.0.0.1:${server.address().port}/index.html`;
  profile = fs.mkdtempSync(path.join(os.tmpdir(), 'web-chromium-'));
  ctx = await chromium.launchPersistentContext(profile, {
    executablePath: '/usr/bin/chromium',
    headless: true,
    viewport: { width: 1280, height: 900 },
    args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
      '--disable-component-update', '--disable-sync'],
  });
  page = ctx.pages()[0] || (await ctx.newPage());
  page.on('pageerror', (e) => pageErrors.push(String(e)));
  page.on('console', (m) => { if (m.type() === 'error') pageErrors.push(m.text()); });
  await page.goto(url);
  await page.waitForFunction(() => window.finger && window.finger.ready === true, null, { timeout: 15000 });
});

after(async () => {
  if (ctx) await ctx.close();
  if (server) server.close();
  if (profile) fs.rmSync(profile, { recursive: true, force: true });
});

/** One console command through the page's console (the board the page talks to). */
const board = (line) => page.evaluate((l) => window.finger.con.command(l, true), line);
const shot = (name, fullPage = false) => page.screenshot({ path: path.join(shots, `web-${name}.png`), fullPage });
const tipOf = (s) => s.split(',').slice(0, 2).map(Number);

test('the page loads: simulated board connected, posture, limits and stop shown', async () => {
  assert.equal(await page.title(), 'finger-fw: the soft finger, live');
  assert.match(await page.textContent('#source'), /simulated board/);
  assert.ok(await page.isVisible('#stop'));
  // the ceiling in force: the same on each channel, at most the board's hold ceiling
  const lim = await page.textContent('#limits');
  const vm = lim.match(/vmax=(\d+\.\d),(\d+\.\d),(\d+\.\d)/);
  assert.ok(vm && vm[1] === vm[2] && vm[2] === vm[3] && Number(vm[1]) > 0 && Number(vm[1]) <= Number(lim.match(/vhold=(\d+\.\d)/)[1]), lim);
  assert.match(await page.textContent('#limits'), /fmax=\d/);
  assert.equal(await page.locator('#board-shape circle').count(), 4, 'nodes 0..3 drawn');
  assert.equal(await page.locator('#board-shape .stack').count(), 3, 'three DE stacks drawn');
  assert.equal(await page.locator('#board-shape .cable').count(), 1);
  assert.equal(await page.locator('#host-shape .host-line').count(), 1, 'host f64 overlay drawn');
  assert.deepEqual(pageErrors, []);
  await shot('loaded');
});

/** Tick labels that read as an axis: numbers, evenly spaced by 1, 2 or 5 times a power of ten,
 * with no more decimals than that step needs, 2 to 8 of them. */
function checkTicks(labels, what) {
  const v = labels.map((l) => Number(l.replace(/ %$/, '')));
  assert.ok(v.every(Number.isFinite) && v.length >= 2 && v.length <= 8, `${what}: ${labels}`);
  const sorted = [...v].sort((a, b) => a - b), step = sorted[1] - sorted[0];
  for (let i = 1; i < sorted.length; i++) assert.ok(Math.abs(sorted[i] - sorted[i - 1] - step) < 1e-9 * Math.max(1, Math.abs(step)), `${what}: uneven ${labels}`);
  const mant = step / 10 ** Math.floor(Math.log10(step) + 1e-12);
  assert.ok([1, 2, 5].some((m) => Math.abs(mant - m) < 1e-6), `${what}: step ${step}`);
  const dec = Math.max(0, -Math.floor(Math.log10(step) + 1e-9));
  for (const l of labels) assert.ok((l.replace(/ %$/, '').split('.')[1] || '').length <= dec, `${what}: ${l} has more decimals than its step ${step}`);
}

test('the drawing has a mm scale bar, the flexor side up, the 33 % limit on every stack; readouts carry units; the stiffness plot is filled from the start', async () => {
  // the stiffness plot before any pose: the present voltages across the tension
  await page.waitForFunction(() => window.finger.plot && window.finger.plot.kind === 'sweep');
  assert.equal(await page.locator('#plot polyline.k1').count(), 1, 'stiffness plot drawn before any pose');
  assert.ok((await page.evaluate(() => window.finger.plot.samples.length)) >= 5);
  // against the voltage, from 0 V to near the ceiling, on ticks that read as an axis
  const vm = Number((await board('limits')).kv.vmax.split(',')[0]);
  const xs = await page.evaluate(() => window.finger.plot.samples.map((s) => s.x));
  assert.ok(xs[0] === 0 && xs[xs.length - 1] >= 0.9 * vm, `voltages ${xs}`);
  checkTicks(await page.locator('#plot text.tick').allTextContents(), 'stiffness y');
  checkTicks(await page.locator('#plot text.xtick').allTextContents(), 'stiffness x');
  // the host's f64 series is drawn on top of the board's, in black, with its own markers
  const order = await page.evaluate(() => [...document.querySelectorAll('#plot polyline')].map((p) => p.getAttribute('class')));
  assert.ok(order.indexOf('host-k1') > order.indexOf('k2'), `host drawn last: ${order}`);
  assert.equal(await page.getAttribute('#plot polyline.host-k1', 'stroke'), '#000');
  assert.ok((await page.locator('#plot rect.host-mark').count()) >= 5);
  // a 10 mm scale bar as long on screen as 10 mm of the finger
  await page.evaluate(() => drawAt(0, [0, 0, 0], 'test'));
  const bar = await page.evaluate(() => document.querySelector('#scale-bar .bar').getBoundingClientRect().toJSON());
  assert.match(await page.textContent('#scale-bar'), /10 mm/);
  const n0 = await page.locator('#node-0').boundingBox(), n3 = await page.locator('#node-3').boundingBox();
  const straight = await board('solve 0 0 0 0');
  const tipX = Number(straight.kv.tip.split(',')[0]);
  const pxPerMm = (n3.x - n0.x) / tipX;
  assert.ok(Math.abs(bar.width / 10 - pxPerMm) < 0.03 * pxPerMm, `bar ${bar.width} px for 10 mm, finger ${pxPerMm} px/mm`);
  // flexor side up: a cable tension lifts the tip on screen
  await page.evaluate(() => drawAt(2, [0, 0, 0], 'test'));
  const tip = await page.locator('#node-3').boundingBox(), base = await page.locator('#node-0').boundingBox();
  assert.ok(tip.y < base.y - 5, `tip ${tip.y} above the base ${base.y}`);
  // the limit on each stack: 2/3 of the stack's rest thickness (the solve at 0 V)
  const marks = page.locator('#board-shape .limit');
  assert.equal(await marks.count(), 3);
  const rest = straight.kv.thick.split(',').map(Number);
  for (let k = 0; k < 3; k++) {
    const lim = Number(await marks.nth(k).getAttribute('data-limit-mm'));
    assert.ok(Math.abs(lim - (2 / 3) * rest[k]) < 1e-3, `joint ${k + 1}: limit ${lim} mm, rest ${rest[k]} mm`);
  }
  // readouts with units
  const ro = await page.textContent('#readout');
  for (const u of [' deg', ' mm', 'N/mm', 'N·mm/rad', 'iters ']) assert.ok(ro.includes(u), `readout lacks ${u}: ${ro}`);
  assert.ok(!/stiffness=/.test(ro), 'no raw key=value stiffness');
  // the voltage colours' scale names the ceiling from limits
  const vmax = (await board('limits')).kv.vmax.split(',')[0];
  assert.ok((await page.textContent('#volt-scale')).includes(`${Number(vmax)} V (ceiling)`));
  // back to the straight finger the next test starts from
  await page.evaluate(() => drawAt(0, [0, 0, 0], 'preview (disarmed, solve)'));
});

test('the WebAssembly board answers the console contract', async () => {
  const v = await board('version');
  assert.match(v.line, /^ok version=\S+ name=finger-fw board=sim$/);
  const st = await board('status');
  for (const k of ['armed', 'force', 'volts', 'thick', 'joints', 'tip', 'cable', 'servo', 'fault']) assert.ok(k in st.kv, `status has ${k}`);
  assert.equal(st.kv.armed, '0');
  assert.equal(st.kv.fault, 'none');
  const lim = await board('limits');
  for (const k of ['vmax', 'vpullin', 'supply', 'fmax']) assert.ok(k in lim.kv, `limits has ${k}`);
  const s = await board('solve 1 0 0 0');
  for (const k of ['joints', 'tip', 'cable', 'thick', 'stiffness', 'iters']) assert.ok(k in s.kv, `solve has ${k}`);
  assert.ok(Number(s.kv.joints.split(',')[0]) > 0, 'flexes under tension');
  const h = await board('help');
  assert.equal(h.line, 'ok');
  assert.ok(h.lines.some((l) => l.startsWith('solve ')) && h.lines.some((l) => l.startsWith('shape ')));
  assert.match((await board('frobnicate')).line, /^err unknown: /);
  assert.match((await board('solve 1 0 0 nan')).line, /^err bad-number: /);
  assert.match((await board('solve -1 0 0 0')).line, /^err usage: /);
  assert.match((await board('volt 1 100')).line, /^err not-armed: /);
  assert.match((await board('solve 1 10000 0 0')).line, /^err limit: /, 'at the ceiling');
  // bytes: CRLF counts once, a blank line gets no reply, an overlong line is err too-long
  const raw = await page.evaluate(() => {
    const b = window.finger.board;
    const prev = b.onText;
    let text = '';
    b.onText = (t) => { text += t; };
    b.write('version\r\n\r\n\nstatus\r' + 'x'.repeat(300) + '\nlimits\n');
    b.onText = prev;
    return text;
  });
  const lines = raw.split('\n').filter((l) => l !== '');
  assert.equal(lines.length, 4, raw);
  assert.match(lines[0], /^ok version=/);
  assert.match(lines[1], /^ok armed=/);
  assert.match(lines[2], /^err too-long: /);
  assert.match(lines[3], /^ok vmax=/);
  // param while armed is refused and changes nothing
  assert.match((await board('arm')).line, /^ok armed=1$/);
  assert.match((await board('param l 30')).line, /^err armed: /);
  assert.match((await board('stop')).line, /^ok stopped$/);
  assert.match((await board('param l')).line, /^ok l=27$/);
});

test('moving the tension slider draws the posture that solve returns', async () => {
  const before = await page.getAttribute('#board-shape', 'data-tip');
  const done0 = await page.evaluate(() => window.finger.previewDone || 0);
  await page.focus('#force');
  for (let i = 0; i < 40; i++) await page.keyboard.press('ArrowRight'); // 40 x 0.05 N
  assert.equal(await page.inputValue('#force'), '2');
  await page.waitForFunction((d) => (window.finger.previewDone || 0) > d && !window.finger.busyPreview
    && document.getElementById('board-shape').dataset.p === '2', done0);
  const drawn = await page.getAttribute('#board-shape', 'data-tip');
  assert.notEqual(drawn, before, 'the drawing moved');
  const s = await board('solve 2 0 0 0');
  const [sx, sy] = tipOf(s.kv.tip), [dx, dy] = tipOf(drawn);
  assert.ok(Math.abs(sx - dx) <= 1e-3 && Math.abs(sy - dy) <= 1e-3, `drawn tip ${drawn} vs solve ${s.kv.tip}`);
  // the drawn tip is node 3's circle
  const cx = Number(await page.getAttribute('#node-3', 'cx')), cy = Number(await page.getAttribute('#node-3', 'cy'));
  assert.ok(Math.abs(cx - sx) <= 1e-3 && Math.abs(cy - sy) <= 1e-3);
  // each drawn node's direction agrees with solve's joint angles: node k's angle = sum of the joints
  const sh = await board('shape 2 0 0 0');
  const joints = s.kv.joints.split(',').map(Number);
  const ang = sh.kv.nodes.split(',').map(Number).filter((_, i) => i % 3 === 2);
  let sum = 0;
  for (let k = 0; k < 3; k++) { sum += joints[k]; assert.ok(Math.abs(ang[k + 1] - sum) <= 0.02, `node ${k + 1}: ${ang[k + 1]} vs ${sum}`); }
  assert.ok(joints[0] > 5, 'bent');
  // the host f64 overlay at the same tension agrees within 0.01 mm at the tip
  const host = tipOf(await page.getAttribute('#host-shape', 'data-tip'));
  assert.ok(Math.hypot(host[0] - sx, host[1] - sy) < 0.01, `host tip ${host}`);
  assert.match(await page.textContent('#readout'), /board: {2}joints [\d.]+, [\d.]+, [\d.]+ deg;/);
  await shot('tension');
});

test('a pose shows its feasible tension interval, the stiffness at both ends, and the plot', async () => {
  for (const [id, v] of [['d1', '10'], ['d2', '10'], ['d3', '10'], ['dp', '']]) await page.fill('#' + id, v);
  await page.click('#pose');
  await page.waitForFunction(() => window.finger.plot && window.finger.plot.kind === 'pose' && window.finger.plot.samples.length === 9);
  const out = await page.textContent('#pose-out');
  const r = await board('pose 10 10 10');
  const [lo, hi] = r.kv.range.split(',');
  assert.ok(out.includes(`feasible tension ${lo} .. ${hi} N`), out);
  assert.match(out, new RegExp(`tip stiffness at ${lo} N: kxx=`));
  assert.match(out, new RegExp(`tip stiffness at ${hi} N: kxx=`));
  assert.equal(await page.locator('#plot polyline.k1').count(), 1);
  // the plotted low end is the board's solve at the low end's voltages
  const lowPose = await board(`pose 10 10 10 ${lo}`);
  const lowSolve = await board(`solve ${lo} ${lowPose.kv.volts.split(',').join(' ')}`);
  const kyy = await page.evaluate(() => window.finger.plot.samples[0].k[1]);
  assert.equal(kyy, Number(lowSolve.kv.stiffness.split(',')[1]));
  await shot('pose', true);
});

test('a pose outside the range shows the board refusal', async () => {
  for (const [id, v] of [['d1', '10'], ['d2', '10'], ['d3', '10'], ['dp', '5']]) await page.fill('#' + id, v);
  await page.click('#pose');
  await page.waitForFunction(() => document.getElementById('refusal').textContent.startsWith('pose 10 10 10 5'));
  const direct = await board('pose 10 10 10 5');
  assert.match(direct.line, /^err unreachable: /);
  assert.equal(await page.textContent('#refusal'), `pose 10 10 10 5  ->  ${direct.line}`);
  assert.equal(await page.getAttribute('#refusal', 'class'), 'mono err');
  assert.equal(await page.textContent('#pose-out'), direct.line);
  await shot('refusal');
  // angles past the branch: the board's own limit text
  for (const [id, v] of [['d1', '120'], ['d2', '120'], ['d3', '120'], ['dp', '']]) await page.fill('#' + id, v);
  await page.click('#pose');
  await page.waitForFunction(() => document.getElementById('refusal').textContent.startsWith('pose 120 120 120 '));
  const lim = await board('pose 120 120 120');
  assert.match(lim.line, /^err limit: /);
  assert.ok((await page.textContent('#refusal')).endsWith(lim.line));
});

/** The gravity arrow's direction on screen: its shaft's unit vector (SVG: x right, y down). */
async function arrowDir() {
  const a = await page.evaluate(() => {
    const l = document.querySelector('#gravity line.arrow');
    return l && ['x1', 'y1', 'x2', 'y2'].map((k) => Number(l.getAttribute(k)));
  });
  assert.ok(a, 'the gravity arrow is drawn');
  const n = Math.hypot(a[2] - a[0], a[3] - a[1]);
  return [(a[2] - a[0]) / n, (a[3] - a[1]) / n];
}

test('the orientation control sets grav_dir at the board, and the drawing points gravity that way', async () => {
  // the board's finger hangs straight down: gravity along the straight finger (+x, right)
  for (const c of ['status', 'limits']) {
    const r = await board(c);
    assert.equal(r.kv.grav, '9.81', c);
    assert.equal(r.kv.grav_dir, '0', c);
  }
  assert.equal(await page.getAttribute('#gravity', 'data-dir'), '0');
  let [ux, uy] = await arrowDir();
  assert.ok(Math.abs(ux - 1) < 1e-3 && Math.abs(uy) < 1e-3, `hanging: ${ux},${uy}`);
  assert.equal(await page.inputValue('#grav-dir'), '0');
  // held horizontally, curling downward: gravity toward the cable side, which is drawn up
  await page.click('.grav-preset[data-dir="90"]');
  await page.waitForFunction(() => document.getElementById('gravity').dataset.dir === '90');
  assert.equal((await board('param grav_dir')).line, 'ok grav_dir=90');
  assert.equal((await board('limits')).kv.grav_dir, '90');
  [ux, uy] = await arrowDir();
  assert.ok(Math.abs(ux) < 1e-3 && Math.abs(uy + 1) < 1e-3, `90: ${ux},${uy}`);
  assert.equal(await page.inputValue('#grav-dir'), '90');
  // the host overlay takes the board's orientation with its other parameters
  assert.equal(await page.evaluate(() => window.finger.params.grav_dir), 90);
  // the slider: -90, curling upward, gravity drawn down
  await page.$eval('#grav-dir', (e) => { e.value = '-90'; e.dispatchEvent(new Event('change')); });
  await page.waitForFunction(() => document.getElementById('gravity').dataset.dir === '-90');
  assert.equal((await board('status')).kv.grav_dir, '-90');
  [ux, uy] = await arrowDir();
  assert.ok(Math.abs(ux) < 1e-3 && Math.abs(uy - 1) < 1e-3, `-90: ${ux},${uy}`);
  assert.match(await page.textContent('#grav-state'), /g 9\.81 m\/s² at -90°/);
  // armed: the board refuses, its refusal is shown, nothing changes
  await page.click('#arm');
  await page.waitForFunction(() => window.finger.armed === true);
  await page.click('.grav-preset[data-dir="0"]');
  await page.waitForFunction(() => document.getElementById('refusal').textContent.startsWith('param grav_dir 0  ->  err armed: '));
  assert.equal((await board('param grav_dir')).line, 'err armed: param only while disarmed');
  assert.equal((await board('status')).kv.grav_dir, '-90');
  assert.equal(await page.inputValue('#grav-dir'), '-90');
  assert.equal(await page.getAttribute('#gravity', 'data-dir'), '-90');
  await page.click('#stop');
  await page.waitForFunction(() => window.finger.armed === false);
  // no gravity: no arrow, the drawing says so
  assert.match((await board('param grav 0')).line, /^ok grav=0$/);
  await page.evaluate(() => readParams());
  assert.equal(await page.locator('#gravity line.arrow').count(), 0);
  assert.match(await page.textContent('#gravity'), /no gravity/);
  // back to the board's finger
  assert.match((await board('preset default')).line, /^ok preset=default$/);
  await page.evaluate(() => readParams());
  assert.equal(await page.getAttribute('#gravity', 'data-dir'), '0');
  assert.equal(await page.inputValue('#grav-dir'), '0');
  assert.deepEqual(pageErrors, []);
});

test('the strip chart gains points while the board runs, and exports them as CSV', async () => {
  const lim = await board('limits');
  const vmax = Math.min(...lim.kv.vmax.split(',').map(Number));
  const v = Math.round(vmax * 0.4 / 100) * 100;
  assert.match((await board('arm')).line, /^ok armed=1/);
  assert.match((await board('force 0.5')).line, /^ok force=/);
  assert.match((await board(`volt all ${v}`)).line, /^ok volts=/);
  const n0 = await page.evaluate(() => window.finger.strip.length);
  await page.waitForFunction((n) => window.finger.strip.length >= n + 8
    && window.finger.strip[window.finger.strip.length - 1].volts[0] > 0, n0, { timeout: 20000 });
  const s = await page.evaluate(() => window.finger.strip.slice(-8));
  for (let i = 1; i < s.length; i++) assert.ok(s[i].t > s[i - 1].t, 'time grows');
  assert.ok(s[s.length - 1].force === 0.5);
  assert.ok(s[s.length - 1].volts[0] > s[0].volts[0] || s[0].volts[0] === v, 'the voltage slews up');
  assert.equal(await page.locator('#strip polyline.strip-tension').count(), 1);
  assert.equal(await page.locator('#strip polyline.strip-voltage').count(), 3);
  assert.equal(await page.locator('#strip polyline.strip-stack').count(), 3);
  assert.equal(await page.locator('#strip polyline.strip-joints').count(), 3);
  // the read-back beside the command and the model: measured voltage, current, sensed thickness
  assert.equal(await page.locator('#strip polyline.strip-voltage-meas').count(), 3);
  assert.equal(await page.locator('#strip polyline.strip-current').count(), 3);
  assert.equal(await page.locator('#strip polyline.strip-stack-meas').count(), 3);
  const last = s[s.length - 1];
  for (let k = 0; k < 3; k++) {
    assert.ok(last.vmeas[k] > 0.5 * last.volts[k] && last.vmeas[k] <= last.volts[k] + 60, `measured ${last.vmeas} for ${last.volts}`);
    assert.ok(Math.abs(last.imeas[k]) < 30, `current ${last.imeas}`);
  }
  const vpts = await page.evaluate(() => document.querySelector('#strip polyline.strip-voltage-meas').getAttribute('points'));
  assert.ok(vpts.split(' ').length >= 8 && !vpts.includes('NaN'), vpts);
  // one colour and one dash per channel, so that equal channels stay visible
  const styles = await page.evaluate(() => [...document.querySelectorAll('#strip polyline.strip-voltage')].map((p) => `${p.getAttribute('stroke')} ${p.getAttribute('stroke-dasharray')} ${p.getAttribute('stroke-width')}`));
  assert.equal(new Set(styles).size, 3, `${styles}`);
  const labels = await page.locator('#strip text.tick').allTextContents();
  assert.ok(labels.length >= 8, `${labels}`);
  // CSV: units in the header, a row a sample
  const csv = await page.evaluate(() => window.finger.stripCsv());
  const rows = csv.trim().split('\n');
  assert.equal(rows[0], 't_s,tension_N,v1_V,v2_V,v3_V,thick1_mm,thick2_mm,thick3_mm,joint1_deg,joint2_deg,joint3_deg'
    + ',vmeas1_V,vmeas2_V,vmeas3_V,imeas1_uA,imeas2_uA,imeas3_uA,thick_meas1_mm,thick_meas2_mm,thick_meas3_mm');
  assert.ok(Number(rows[rows.length - 1].split(',')[11]) > 0, rows[rows.length - 1]);
  assert.ok(rows.length - 1 >= n0 + 8);
  assert.equal(Number(rows[rows.length - 1].split(',')[1]), 0.5);
  // the button downloads it
  const [dl] = await Promise.all([page.waitForEvent('download'), page.click('#strip-csv')]);
  assert.equal(dl.suggestedFilename(), 'finger-status.csv');
  await shot('strip');
  assert.match((await board('stop')).line, /^ok stopped$/);
  await page.waitForFunction(() => window.finger.armed === false);
});

test('stop is always reachable and stops the board at once', async () => {
  await page.click('#arm');
  await page.waitForFunction(() => window.finger.armed === true);
  assert.match((await board('force 1')).line, /^ok force=1\.000 /);
  // a voltage well inside the ceiling in force (`limits`' vmax: the board's film sets it)
  const vmax = Number((await board('limits')).line.match(/ vmax=([0-9.]+),/)[1]);
  const v = Math.floor(0.6 * vmax / 100) * 100; // on the sliders' 50 V steps
  assert.match((await board(`volt all ${v}`)).line, new RegExp(`^ok volts=${v}\\.0,${v}\\.0,${v}\\.0$`));
  await page.waitForFunction(() => window.finger.status && Number(window.finger.status.volts.split(',')[0]) > 0);
  // visible and on top, in a small window and scrolled to the bottom
  for (const vp of [{ width: 1280, height: 900 }, { width: 760, height: 520 }]) {
    await page.setViewportSize(vp);
    await page.evaluate(() => window.scrollTo(0, document.body.scrollHeight));
    const box = await page.locator('#stop').boundingBox();
    assert.ok(box && box.y >= 0 && box.x >= 0 && box.x + box.width <= vp.width && box.y + box.height <= vp.height, JSON.stringify(box));
    const top = await page.evaluate(([x, y]) => document.elementFromPoint(x, y).id, [box.x + box.width / 2, box.y + box.height / 2]);
    assert.equal(top, 'stop');
  }
  await page.setViewportSize({ width: 1280, height: 900 });
  await page.evaluate(() => window.scrollTo(0, 0));
  // armed, the sliders move the board: tension by the keyboard, a voltage past the ceiling refused
  await page.focus('#force');
  await page.keyboard.press('ArrowRight');
  await page.waitForFunction(() => window.finger.status && window.finger.status.force === '1.050');
  await page.focus('#v1');
  await page.keyboard.press('End');
  await page.waitForFunction(() => document.getElementById('refusal').textContent.startsWith('volt 1 '));
  assert.ok(Number((await page.textContent('#refusal')).split(' ')[2]) >= vmax, 'the slider reaches past the ceiling');
  assert.match(await page.textContent('#refusal'), new RegExp(`^volt 1 \\d+ {2}-> {2}err limit: channel 1: \\d+\\.\\d V is at or past the ceiling ${vmax.toFixed(1).replace('.', '\\.')} V`));
  assert.equal((await board('status')).kv.target, `${v}.0,${v}.0,${v}.0`, 'the refusal changed nothing');
  await page.waitForFunction((x) => document.getElementById('v1').value === String(x), v);
  await page.waitForFunction(() => Number(window.finger.status.volts.split(',')[0]) >= 2000);
  await shot('armed');
  // commands queued behind each other: stop goes first
  await page.evaluate(() => { for (let i = 0; i < 5; i++) window.finger.con.command('solve 1 0 0 0', true).catch(() => {}); });
  await page.click('#stop');
  await page.waitForFunction(() => document.getElementById('refusal').textContent === 'stop  ->  ok stopped');
  const st = await board('status');
  assert.equal(st.kv.armed, '0');
  assert.equal(st.kv.volts, '0.0,0.0,0.0', 'HV to 0 at once');
  assert.equal(st.kv.force, '0.000');
  assert.equal(st.kv.enable, '0');
  await page.waitForFunction(() => document.getElementById('armed-state').textContent === 'disarmed');
  // the keyboard's Escape is a stop too
  assert.match((await board('arm')).line, /^ok armed=1$/);
  await page.keyboard.press('Escape');
  await page.waitForFunction(() => window.finger.armed === false);
  assert.equal((await board('status')).kv.armed, '0');
  await shot('stopped');
  assert.deepEqual(pageErrors, []);
});

test('a board over Web Serial (a stand-in port: a second wasm board behind CRLF, without shape)', async () => {
  const p2 = await ctx.newPage();
  const errs = [];
  p2.on('pageerror', (e) => errs.push(String(e)));
  await p2.addInitScript(() => {
    // navigator.serial with one port: bytes to a second finger-wasm instance, replies in CRLF
    // as the board writes them, after its boot line; `shape` answered as a build without it
    const port = {
      async open() {
        const bin = Uint8Array.from(atob(window.FINGER_WASM_B64), (c) => c.charCodeAt(0));
        const e = (await WebAssembly.instantiate(bin, {})).instance.exports;
        const enc = new TextEncoder(), dec = new TextDecoder();
        let rx, line = '';
        this.readable = new ReadableStream({ start(c) { rx = c; } });
        const take = () => {
          const p = e.out_ptr(), n = e.out_len();
          if (!n) return null;
          const t = dec.decode(new Uint8Array(e.memory.buffer, p, n).slice());
          e.out_clear();
          return enc.encode(t.replace(/\n/g, '\r\n'));
        };
        const out = () => { const t = take(); if (t) rx.enqueue(t); };
        const run = (s) => { const b = enc.encode(s); const p = e.io_buf(); new Uint8Array(e.memory.buffer, p, b.length).set(b); e.fw_input(b.length); };
        const feed = (s) => { run(s); out(); };
        this.writable = new WritableStream({
          write(chunk) {
            for (const ch of dec.decode(chunk)) {
              line += ch;
              if (ch !== '\n') continue;
              if (/^shape\b/i.test(line.trim())) rx.enqueue(enc.encode('err unknown: unknown command shape; try help\r\n'));
              // `solve` as a board's busy command side answers it: late, so that a `stop` sent
              // meanwhile is answered first (docs/console.md "Lines")
              else if (/^solve\b/i.test(line.trim())) { run(line); const t = take(); setTimeout(() => rx.enqueue(t), 300); }
              else feed(line);
              line = '';
            }
          },
        });
        setInterval(() => { e.fw_tick(20); out(); }, 20);
        rx.enqueue(enc.encode('# finger-fw 0.1.0 ready\r\n'));
      },
    };
    Object.defineProperty(navigator, 'serial', { value: { requestPort: async () => port }, configurable: true });
  });
  await p2.goto(url);
  await p2.waitForFunction(() => window.finger && window.finger.ready === true);
  await p2.click('#use-serial');
  await p2.waitForFunction(() => window.finger.ready === true && document.getElementById('source').textContent === 'board over Web Serial');
  const cmd2 = (l) => p2.evaluate((x) => window.finger.con.command(x, true), l);
  assert.match((await cmd2('version')).line, /^ok version=.* board=sim$/);
  assert.equal(await p2.evaluate(() => window.finger.hasShape), false);
  assert.match(await p2.textContent('#view-mode'), /board has no shape/);
  // the drawing falls back to the host's geometry at the board's state; its tip is the board's
  await p2.focus('#force');
  for (let i = 0; i < 20; i++) await p2.keyboard.press('ArrowRight');
  await p2.waitForFunction(() => document.getElementById('board-shape').dataset.p === '1' && !window.finger.busyPreview);
  const s = await cmd2('solve 1 0 0 0');
  const [sx, sy] = tipOf(s.kv.tip), [dx, dy] = tipOf(await p2.getAttribute('#board-shape', 'data-tip'));
  assert.ok(Math.hypot(sx - dx, sy - dy) < 0.01, `${s.kv.tip} vs drawn ${dx},${dy}`);
  assert.match((await cmd2('arm')).line, /^ok armed=1$/);
  // a stop while a command runs: `ok stopped` comes first, then the command's own reply;
  // each goes to its own command
  const solving = p2.evaluate(() => window.finger.con.command('solve 0.5 0 0 0', true));
  await p2.waitForFunction(() => window.finger.con.sent.some((c) => c.line === 'solve 0.5 0 0 0'));
  await p2.click('#stop');
  await p2.waitForFunction(() => document.getElementById('refusal').textContent === 'stop  ->  ok stopped');
  assert.match((await solving).line, /^ok joints=/);
  assert.equal((await cmd2('status')).kv.armed, '0');
  assert.deepEqual(errs, []);
  await p2.close();
});
