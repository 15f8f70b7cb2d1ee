// The page `gapflow serve` hands to the browser: a canvas drawn from /geometry and
// /state (polled JSON, no reloads) and controls that POST to /pause, /resume,
// /restart and /set. Query parameters ?set=key=value (repeatable) are applied on
// load through the same path as the controls (used by the headless-browser test).
// Colours match view/top_view.cpp.
#pragma once

namespace gapflow {

inline constexpr const char* kLivePage = R"HTML(<!doctype html>
<html><head><meta charset="utf-8"><title>gapflow live</title>
<style>
body { font: 13px sans-serif; margin: 8px; display: flex; gap: 14px; }
#side { width: 330px; } canvas { border: 1px solid #888; background: #fff; }
table { border-collapse: collapse; } td { padding: 1px 6px; } .num { font-family: monospace; }
fieldset { margin: 6px 0; } #msg.err { color: #b00; white-space: pre-wrap; } #msg.ok { color: #070; }
input[type=number] { width: 70px; }
</style></head>
<body>
<canvas id="board" width="420" height="980"></canvas>
<div id="side">
<h3 id="title">gapflow</h3>
<table>
<tr><td>phase</td><td id="phase" class="num"></td></tr>
<tr><td>t (s)</td><td id="t" class="num"></td></tr>
<tr><td>passed</td><td id="passed" class="num"></td></tr>
<tr><td>J so far (1/s)</td><td id="J" class="num"></td></tr>
<tr><td>clogs</td><td id="clogs" class="num"></td></tr>
<tr><td>real-time factor</td><td id="rtf" class="num"></td></tr>
</table>
<fieldset><legend>run</legend>
<button id="pause">pause</button> <button id="restart">restart</button>
<label><input type="checkbox" id="bystate"> colour by state</label></fieldset>
<fieldset><legend>obstruction</legend>
shape <select id="shape"><option>none</option><option>cylinder</option><option>A</option><option>V</option></select>
<button data-key="obstruction.shape" data-src="shape" data-quote="1">set</button><br>
distance D (mm) <input type="number" id="distance" step="1">
<button data-key="obstruction.distance_mm" data-src="distance">set</button></fieldset>
<fieldset><legend>bottleneck</legend>
gap W (mm) <input type="number" id="gap" step="0.5">
<button data-key="bottleneck.gap_mm" data-src="gap">set</button></fieldset>
<fieldset><legend>shaking</legend>
walls <select id="wshake"><option>true</option><option>false</option></select>
<button data-key="shaking.walls.enabled" data-src="wshake">set</button>
amplitude (mm) <input type="number" id="wamp" step="0.1">
<button data-key="shaking.walls.amplitude_mm" data-src="wamp">set</button><br>
obstruction <select id="oshake"><option>true</option><option>false</option></select>
<button data-key="shaking.obstruction.enabled" data-src="oshake">set</button>
amplitude (mm) <input type="number" id="oamp" step="0.1">
<button data-key="shaking.obstruction.amplitude_mm" data-src="oamp">set</button></fieldset>
<div id="msg"></div>
<h4>scenario now</h4><table id="settings"></table>
<div>changes (--set): <span id="overrides" class="num"></span></div>
</div>
<script>
const V = [[68,1,84],[72,36,117],[59,82,139],[44,114,142],[33,145,140],[40,174,128],[94,201,98],[173,220,48],[253,231,37]];
const STATE = ['rgb(49,114,204)', 'rgb(220,38,28)', 'rgb(150,150,150)', 'rgb(240,160,40)'];
const SPEED_MAX = 500;  // mm/s, top of the colour scale (as the snapshots' default)
function viridis(s) {
  const u = Math.min(Math.max(s / SPEED_MAX, 0), 1) * 8, i = Math.min(7, Math.floor(u)), f = u - i;
  const c = V[i].map((a, k) => Math.round(a + f * (V[i + 1][k] - a)));
  return `rgb(${c[0]},${c[1]},${c[2]})`;
}
let geo = null, generation = -1, paused = false;
const cv = document.getElementById('board'), cx = cv.getContext('2d');
function view() {  // mm -> px, uphill up
  const w = geo.width_mm + 2 * geo.wall_mm + 10, h = geo.length_mm + geo.wall_mm + 5 + 60;
  const s = Math.min(cv.width / w, cv.height / h);
  return {s, x0: -w / 2, y1: geo.length_mm + geo.wall_mm + 5};
}
function poly(v, pts, off) {
  cx.beginPath();
  pts.forEach((p, i) => { const X = (p[0] + off[0] - v.x0) * v.s, Y = (v.y1 - p[1] - off[1]) * v.s;
    i ? cx.lineTo(X, Y) : cx.moveTo(X, Y); });
  cx.closePath(); cx.fill();
}
function draw(st) {
  if (!geo) return;
  const v = view(), o = st.offsets || {lw: [0, 0], rw: [0, 0], ob: [0, 0]};
  cx.fillStyle = '#fff'; cx.fillRect(0, 0, cv.width, cv.height);
  cx.fillStyle = 'rgb(246,243,232)'; cx.fillRect(0, 0, cv.width, (v.y1 + 60) * v.s);
  cx.fillStyle = 'rgb(60,62,70)';
  geo.walls.forEach((w, i) => poly(v, w, i == 0 ? o.lw : i == 1 ? o.rw : [0, 0]));
  cx.fillStyle = 'rgb(140,90,50)';
  if (geo.obstruction && geo.obstruction.r) {
    cx.beginPath();
    cx.arc((geo.obstruction.c[0] + o.ob[0] - v.x0) * v.s, (v.y1 - geo.obstruction.c[1] - o.ob[1]) * v.s,
           geo.obstruction.r * v.s, 0, 2 * Math.PI);
    cx.fill();
  } else if (geo.obstruction) poly(v, geo.obstruction.v, o.ob);
  const bystate = document.getElementById('bystate').checked, p = st.p || [];
  for (let i = 0; i < p.length; i += 5) {
    cx.fillStyle = bystate ? STATE[p[i + 4]] : viridis(p[i + 3]);
    cx.beginPath();
    cx.arc((p[i] - v.x0) * v.s, (v.y1 - p[i + 1]) * v.s, Math.max(p[i + 2] * v.s, 1), 0, 2 * Math.PI);
    cx.fill();
  }
  cx.strokeStyle = 'rgb(217,26,140)'; cx.lineWidth = 2; cx.beginPath();
  cx.moveTo((geo.tips[0][0] + o.lw[0] - v.x0) * v.s, (v.y1 - geo.tips[0][1]) * v.s);
  cx.lineTo((geo.tips[1][0] + o.rw[0] - v.x0) * v.s, (v.y1 - geo.tips[1][1]) * v.s); cx.stroke();
}
async function loadGeometry() {
  geo = await (await fetch('/geometry')).json();
  document.getElementById('title').textContent = `${geo.name} (${geo.model})`;
  const s = geo.settings, t = document.getElementById('settings');
  t.innerHTML = '';
  for (const k in s) t.insertAdjacentHTML('beforeend', `<tr><td>${k}</td><td class="num" id="set-${k}">${s[k]}</td></tr>`);
  document.getElementById('shape').value = s['obstruction.shape'];
  document.getElementById('distance').value = s['obstruction.distance_mm'];
  document.getElementById('gap').value = s['bottleneck.gap_mm'];
  document.getElementById('wshake').value = String(s['shaking.walls.enabled']);
  document.getElementById('wamp').value = s['shaking.walls.amplitude_mm'];
  document.getElementById('oshake').value = String(s['shaking.obstruction.enabled']);
  document.getElementById('oamp').value = s['shaking.obstruction.amplitude_mm'];
  document.getElementById('overrides').textContent = geo.overrides.join('  ') || '(none)';
}
async function poll() {
  try {
    const st = await (await fetch('/state')).json();
    if (st.generation !== generation || !geo) { generation = st.generation; await loadGeometry(); }
    paused = st.paused;
    document.getElementById('pause').textContent = paused ? 'resume' : 'pause';
    document.getElementById('phase').textContent = st.phase + (paused ? ' (paused)' : '') + (st.clogged ? ' CLOGGED' : '');
    const f = (k, n) => document.getElementById(k).textContent = st[k] === undefined ? '' : Number(st[k]).toFixed(n);
    f('t', 2); f('passed', 0); f('J', 1); f('clogs', 0); f('rtf', 2);
    draw(st);
  } catch (e) { document.getElementById('phase').textContent = 'no connection'; }
  setTimeout(poll, 100);
}
function message(ok, text) { const m = document.getElementById('msg'); m.className = ok ? 'ok' : 'err'; m.textContent = text; }
async function send(assignment) {
  const r = await fetch('/set', {method: 'POST', body: assignment});
  message(r.ok, await r.text());
  if (r.ok) { generation = -1; }
}
document.querySelectorAll('button[data-key]').forEach(b => b.onclick = () => {
  const v = document.getElementById(b.dataset.src).value;
  send(`${b.dataset.key}=${b.dataset.quote ? '"' + v + '"' : v}`);
});
document.getElementById('pause').onclick = () => fetch(paused ? '/resume' : '/pause', {method: 'POST'});
document.getElementById('restart').onclick = () => fetch('/restart', {method: 'POST'});
(async () => {
  for (const a of new URLSearchParams(location.search).getAll('set')) await send(a);
  poll();
})();
</script>
</body></html>
)HTML";

}  // namespace gapflow
