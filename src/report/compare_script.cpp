// The script of the interactive comparison (compare_view.hpp): plain JS, no library, reading
// the page's JSON block and drawing with DOM calls and textContent only.
#include "physgrad/report/compare_view.hpp"

namespace physgrad {

const std::string_view kCompareScript = R"JS((function () {
'use strict';
var SVG = 'http://www.w3.org/2000/svg';
var box = document.getElementById('pg-compare');
var block = document.getElementById('pg-compare-data');
if (!box || !block) return;
var data = JSON.parse(block.textContent), runs = data.runs;
var W = 760, H = 360, L = 64, R = 12, T = 12, B = 44;
var st = {metric: '', x: 'iteration', log: false, smooth: 0, view: null,
  on: runs.map(function (r, i) { return i < 12; }), hidden: runs.map(function () { return false; })};
function el(tag, text, cls) {
  var e = document.createElement(tag);
  if (text !== undefined) e.textContent = text;
  if (cls) e.className = cls;
  return e;
}
function sv(tag, attrs) {
  var e = document.createElementNS(SVG, tag);
  for (var k in attrs) e.setAttribute(k, attrs[k]);
  return e;
}
var colours = ['#1f77b4', '#d62728', '#2ca02c', '#ff7f0e', '#9467bd', '#8c564b', '#e377c2',
  '#7f7f7f', '#bcbd22', '#17becf'];
var metrics = [];
runs.forEach(function (r) {
  Object.keys(r.c).forEach(function (k) {
    if (k !== 'iteration' && k !== 'wall_seconds' && metrics.indexOf(k) < 0) metrics.push(k);
  });
});
metrics.sort(function (a, b) { return (b === 'test_loss') - (a === 'test_loss') ||
  (b === 'loss') - (a === 'loss') || (a < b ? -1 : a > b ? 1 : 0); });
st.metric = metrics[0] || '';
var controls = el('div', undefined, 'pg-controls');
var metricSel = el('select'); metricSel.id = 'pg-metric';
metrics.forEach(function (m) { var o = el('option', m); o.value = m; metricSel.appendChild(o); });
metricSel.onchange = function () { st.metric = metricSel.value; st.view = null; draw(); };
var xBtn = el('button', 'x: per update'); xBtn.id = 'pg-x'; xBtn.type = 'button';
xBtn.onclick = function () { st.x = st.x === 'iteration' ? 'wall_seconds' : 'iteration';
  xBtn.textContent = st.x === 'iteration' ? 'x: per update' : 'x: per second'; st.view = null; draw(); };
var logBox = el('input'); logBox.type = 'checkbox'; logBox.id = 'pg-log';
logBox.onchange = function () { st.log = logBox.checked; st.view = null; draw(); };
var slider = el('input'); slider.type = 'range'; slider.min = '0'; slider.max = '0.99';
slider.step = '0.01'; slider.value = '0'; slider.id = 'pg-smooth';
var smoothText = el('span', '0');
slider.oninput = function () { st.smooth = +slider.value; smoothText.textContent = slider.value; draw(); };
var csvBtn = el('button', 'download CSV'); csvBtn.id = 'pg-csv'; csvBtn.type = 'button';
var lab = function (t, c) { var l = el('label', t + ' '); l.appendChild(c); return l; };
[lab('metric', metricSel), xBtn, lab('log y', logBox), lab('smoothing', slider), smoothText,
  csvBtn].forEach(function (c) { controls.appendChild(c); });
box.appendChild(controls);
var picker = el('details', undefined, 'pg-picker');
picker.appendChild(el('summary', 'runs (' + runs.length + ')'));
var groups = {};
runs.forEach(function (r, i) {
  if (!groups[r.g]) { groups[r.g] = el('fieldset'); groups[r.g].appendChild(el('legend', r.g));
    picker.appendChild(groups[r.g]); }
  var c = el('input'); c.type = 'checkbox'; c.checked = st.on[i]; c.className = 'pg-pick';
  c.setAttribute('data-run', i);
  c.onchange = function () { st.on[i] = c.checked; st.view = null; draw(); };
  groups[r.g].appendChild(lab(r.l + (r.s !== '' ? ' seed ' + r.s : ''), c));
});
box.appendChild(picker);
var svg = sv('svg', {viewBox: '0 0 ' + W + ' ' + H, 'class': 'pg-plot', role: 'img'});
box.appendChild(svg);
var readout = el('div', '', 'pg-readout'); box.appendChild(readout);
var legend = el('div', undefined, 'pg-legend'); box.appendChild(legend);
function series(i) {
  var r = runs[i], xs = r.c[st.x], ys = r.c[st.metric], out = [], s = 0, w = 0;
  if (!xs || !ys) return out;
  for (var k = 0; k < xs.length; k++) {
    var y = ys[k];
    if (typeof y !== 'number' || !isFinite(y) || typeof xs[k] !== 'number') continue;
    if (st.smooth > 0) { s = st.smooth * s + (1 - st.smooth) * y; w = st.smooth * w + (1 - st.smooth);
      y = s / w; }
    if (st.log && !(y > 0)) continue;
    out.push([xs[k], y]);
  }
  return out;
}
function shown() { var v = []; st.on.forEach(function (o, i) { if (o && !st.hidden[i]) v.push(i); });
  return v; }
function ty(y) { return st.log ? Math.log(y) / Math.LN10 : y; }
function bounds(all) {
  var b = [Infinity, -Infinity, Infinity, -Infinity];
  all.forEach(function (p) { p.forEach(function (q) { b[0] = Math.min(b[0], q[0]);
    b[1] = Math.max(b[1], q[0]); b[2] = Math.min(b[2], ty(q[1])); b[3] = Math.max(b[3], ty(q[1])); }); });
  if (!(b[0] < b[1])) { b[0] -= 1; b[1] += 1; }
  if (!(b[2] < b[3])) { b[2] -= 1; b[3] += 1; }
  return b;
}
function fmt(v) { return Math.abs(v) >= 1e4 || (Math.abs(v) < 1e-3 && v !== 0) ? v.toExponential(2)
  : String(+v.toPrecision(4)); }
var cur = {b: null, data: {}};
function px(x) { var b = cur.b; return L + (x - b[0]) / (b[1] - b[0]) * (W - L - R); }
function py(y) { var b = cur.b; return H - B - (ty(y) - b[2]) / (b[3] - b[2]) * (H - T - B); }
function draw() {
  // The plot's width in user units follows its box, so that its text stays 12 px at any width.
  W = Math.max(300, Math.min(900, box.clientWidth || 760));
  svg.setAttribute('viewBox', '0 0 ' + W + ' ' + H);
  while (svg.firstChild) svg.removeChild(svg.firstChild);
  while (legend.firstChild) legend.removeChild(legend.firstChild);
  var vis = shown(), all = [];
  cur.data = {};
  vis.forEach(function (i) { cur.data[i] = series(i); all.push(cur.data[i]); });
  cur.b = st.view || bounds(all);
  var b = cur.b, clip = sv('clipPath', {id: 'pg-clip'});
  clip.appendChild(sv('rect', {x: L, y: T, width: W - L - R, height: H - T - B}));
  svg.appendChild(clip);
  svg.appendChild(sv('rect', {x: L, y: T, width: W - L - R, height: H - T - B, fill: 'none',
    stroke: '#999'}));
  for (var k = 0; k <= 4; k++) {
    var xv = b[0] + (b[1] - b[0]) * k / 4, yv = b[2] + (b[3] - b[2]) * k / 4;
    var xt = sv('text', {x: px(xv), y: H - B + 16, 'text-anchor': 'middle', 'font-size': 12});
    xt.textContent = fmt(xv); svg.appendChild(xt);
    var yt = sv('text', {x: L - 4, y: H - B - (H - T - B) * k / 4 + 4, 'text-anchor': 'end',
      'font-size': 12, 'class': 'pg-ytick'});
    yt.textContent = st.log ? '1e' + fmt(yv) : fmt(yv); svg.appendChild(yt);
  }
  var xl = sv('text', {x: (L + W - R) / 2, y: H - 6, 'text-anchor': 'middle', 'font-size': 13,
    id: 'pg-xlabel'});
  xl.textContent = st.x === 'iteration' ? 'updates (iteration)' : 'time (s)';
  svg.appendChild(xl);
  var yl = sv('text', {x: 14, y: (T + H - B) / 2, 'text-anchor': 'middle', 'font-size': 13,
    transform: 'rotate(-90 14 ' + (T + H - B) / 2 + ')', id: 'pg-ylabel'});
  yl.textContent = st.metric + (st.log ? ' (log scale)' : '') +
    (st.smooth > 0 ? ', EMA ' + st.smooth : '');
  svg.appendChild(yl);
  vis.forEach(function (i) {
    var p = cur.data[i]; if (!p.length) return;
    var d = p.map(function (q, n) { return (n ? 'L' : 'M') + px(q[0]).toFixed(1) + ' ' +
      py(q[1]).toFixed(1); }).join('');
    svg.appendChild(sv('path', {d: d, fill: 'none', stroke: colours[i % 10], 'stroke-width': 1.5,
      'clip-path': 'url(#pg-clip)', 'class': 'pg-run', 'data-run': i}));
  });
  st.on.forEach(function (o, i) {
    if (!o) return;
    var e = el('span', runs[i].g + ': ' + runs[i].l + (runs[i].s !== '' ? ' seed ' + runs[i].s : ''),
      'pg-entry' + (st.hidden[i] ? ' pg-off' : ''));
    e.style.borderColor = colours[i % 10]; e.setAttribute('data-run', i);
    e.onclick = function () { st.hidden[i] = !st.hidden[i]; draw(); };
    legend.appendChild(e);
  });
}
function toData(ev) {
  var r = svg.getBoundingClientRect(), b = cur.b;
  var sx = (ev.clientX - r.left) * W / r.width, sy = (ev.clientY - r.top) * H / r.height;
  return [b[0] + (sx - L) / (W - L - R) * (b[1] - b[0]),
    b[2] + (H - B - sy) / (H - T - B) * (b[3] - b[2]), sx, sy];
}
var drag = null;
svg.addEventListener('mousedown', function (ev) { drag = toData(ev); ev.preventDefault(); });
svg.addEventListener('mouseup', function (ev) {
  if (!drag) return;
  var e = toData(ev), d = drag; drag = null;
  if (Math.abs(e[2] - d[2]) < 4 || Math.abs(e[3] - d[3]) < 4) return;
  st.view = [Math.min(d[0], e[0]), Math.max(d[0], e[0]), Math.min(d[1], e[1]), Math.max(d[1], e[1])];
  draw();
});
svg.addEventListener('wheel', function (ev) {
  ev.preventDefault();
  var p = toData(ev), b = cur.b.slice(), f = ev.deltaY < 0 ? 0.8 : 1.25;
  st.view = [p[0] - (p[0] - b[0]) * f, p[0] + (b[1] - p[0]) * f, b[2], b[3]];
  draw();
}, {passive: false});
svg.addEventListener('dblclick', function () { st.view = null; draw(); });
svg.addEventListener('mousemove', function (ev) {
  var x = toData(ev)[0], parts = [st.x + ' = ' + fmt(x)];
  shown().forEach(function (i) {
    var p = cur.data[i] || [], v = null;
    for (var k = 0; k < p.length && p[k][0] <= x; k++) v = p[k][1];
    if (v !== null) parts.push(runs[i].l + (runs[i].s !== '' ? ' seed ' + runs[i].s : '') + ': ' + fmt(v));
  });
  readout.textContent = parts.join(' · ');
});
function quote(t) { t = String(t); return /[",\n\r]/.test(t) ? '"' + t.replace(/"/g, '""') + '"' : t; }
function csv() {
  var lines = ['group,label,seed,run,' + quote(st.x) + ',' + quote(st.metric)];
  shown().forEach(function (i) { series(i).forEach(function (q) {
    lines.push([quote(runs[i].g), quote(runs[i].l), quote(runs[i].s), i, q[0], q[1]].join(','));
  }); });
  return lines.join('\n') + '\n';
}
window.physgradCompareCsv = csv;
csvBtn.onclick = function () {
  var a = el('a'); a.href = URL.createObjectURL(new Blob([csv()], {type: 'text/csv'}));
  a.download = 'curves.csv'; document.body.appendChild(a); a.click(); a.remove();
};
draw();
})();
)JS";

}  // namespace physgrad
