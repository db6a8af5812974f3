#include "traffic_sim_view.hpp"

#include <cmath>
#include <nlohmann/json.hpp>

#include "site_svg.hpp"

namespace fleet::ctl {
namespace {

// The page's script: reads DATA, draws frame k on the overlay. Kept small and dependency-free.
constexpr const char* kScript = R"JS(
const D = DATA, F = D.frame, ov = document.getElementById('ov');
const X = x => F.pad + (x - F.ox) * F.scale, Y = y => F.top + (F.h - (y - F.oy)) * F.scale;
const NS = 'http://www.w3.org/2000/svg';
const colours = ['#e6194b','#3cb44b','#4363d8','#f58231','#911eb4','#42d4f4','#f032e6','#9a6324',
  '#800000','#469990','#000075','#808000','#ffe119','#a9a9a9','#fabed4','#dcbeff','#aaffc3','#ffd8b1'];
const col = i => colours[i % colours.length];
const slider = document.getElementById('t'), label = document.getElementById('lbl');
slider.max = D.frames.length - 1;
function el(name, attrs) { const e = document.createElementNS(NS, name);
  for (const k in attrs) e.setAttribute(k, attrs[k]); return e; }
function path(nodes) { return nodes.map((v, i) => (i ? 'L' : 'M') + X(D.nodes[v][0]).toFixed(1) + ' ' +
  Y(D.nodes[v][1]).toFixed(1)).join(' '); }
function draw(k) {
  const f = D.frames[k];
  ov.replaceChildren();
  f.r.forEach((r, i) => {
    const [x, y, phase, dwell, target, base, horizon] = r;
    if (horizon.length) ov.appendChild(el('path', {d: path([base[base.length - 1], ...horizon]),
      stroke: col(i), 'stroke-width': 2, 'stroke-dasharray': '4 3', fill: 'none', opacity: 0.7}));
    if (base.length > 1) ov.appendChild(el('path', {d: path(base), stroke: col(i), 'stroke-width': 5,
      fill: 'none', opacity: 0.8, 'stroke-linecap': 'round'}));
    if (target >= 0 && document.getElementById('goals').checked) ov.appendChild(el('line', {x1: X(x),
      y1: Y(y), x2: X(D.nodes[target][0]), y2: Y(D.nodes[target][1]), stroke: col(i), 'stroke-width': 0.8,
      opacity: 0.5}));
  });
  f.r.forEach((r, i) => {
    const [x, y, phase, dwell] = r;
    ov.appendChild(el('circle', {cx: X(x), cy: Y(y), r: D.radius * F.scale, fill: col(i),
      stroke: dwell ? '#000' : (phase ? '#fff' : '#333'), 'stroke-width': dwell ? 3 : 1.5}));
    const t = el('text', {x: X(x), y: Y(y) + 4, 'text-anchor': 'middle', 'font-size': 11,
      fill: '#000', 'font-weight': 'bold'}); t.textContent = i; ov.appendChild(t);
  });
  label.textContent = `t = ${f.t.toFixed(1)} s · ${f.done} tasks done · ${f.r.length} robots`;
  slider.value = k;
}
let k = 0, timer = null;
function play() { if (timer) { clearInterval(timer); timer = null; return; }
  timer = setInterval(() => { k = Math.min(k + +document.getElementById('speed').value, D.frames.length - 1);
    draw(k); if (k >= D.frames.length - 1) { clearInterval(timer); timer = null; } }, 100); }
document.getElementById('play').onclick = play;
document.getElementById('back').onclick = () => { k = Math.max(0, k - 1); draw(k); };
document.getElementById('fwd').onclick = () => { k = Math.min(D.frames.length - 1, k + 1); draw(k); };
slider.oninput = () => { k = +slider.value; draw(k); };
document.getElementById('goals').onchange = () => draw(k);
const q = new URLSearchParams(location.search).get('t');
if (q !== null) k = Math.max(0, Math.min(D.frames.length - 1, D.frames.findIndex(f => f.t >= +q)));
if (k < 0) k = D.frames.length - 1;
draw(k);
)JS";

}  // namespace

std::string trafficSimHtml(const site::Site& site, const traffic::Roadmap& roadmap,
                           const traffic::VirtualFleetResult& result, const std::string& title) {
  const SvgFrame f = siteSvgFrame(site);
  nlohmann::json d;
  d["frame"] = {{"ox", f.origin.x}, {"oy", f.origin.y}, {"h", f.height},
                {"scale", f.scale}, {"pad", f.pad},     {"top", f.top}};
  d["radius"] = roadmap.options.radius;
  auto& nodes = d["nodes"] = nlohmann::json::array();
  for (std::size_t v = 0; v < roadmap.graph.size(); ++v) {
    const Vec2 p = roadmap.graph.position(static_cast<traffic::NodeId>(v));
    // Centimetres are plenty and keep long runs' pages small.
    nodes.push_back({std::round(p.x * 100.0) / 100.0, std::round(p.y * 100.0) / 100.0});
  }
  auto& frames = d["frames"] = nlohmann::json::array();
  for (const auto& fr : result.frames) {
    nlohmann::json robots = nlohmann::json::array();
    for (const auto& r : fr.robots) {
      robots.push_back({std::round(r.position.x * 100.0) / 100.0, std::round(r.position.y * 100.0) / 100.0,
                        r.phase, r.dwelling ? 1 : 0, r.target, r.base, r.horizon});
    }
    frames.push_back(
        {{"t", std::round(fr.time * 10.0) / 10.0}, {"done", fr.tasksDone}, {"r", std::move(robots)}});
  }
  std::string json = d.dump();
  // The data sits in a <script>: keep a "</" in it from ending the element.
  for (std::size_t i = 0; (i = json.find("</", i)) != std::string::npos; i += 3)
    json.replace(i, 2, "<\\/");
  std::string html;
  html += "<!doctype html>\n<html><head><meta charset=\"utf-8\"><title>";
  html += title;
  html +=
      "</title>\n<style>body{font-family:DejaVu Sans,Arial,sans-serif;margin:8px}"
      "#stage{position:relative}#stage svg{position:absolute;left:0;top:0}"
      "#bar{margin:4px 0 8px}#bar input[type=range]{width:600px;vertical-align:middle}</style></head>\n"
      "<body><div id=\"bar\"><b>";
  html += title;
  html +=
      "</b> <button id=\"back\">&lt;</button> <button id=\"play\">play / pause</button> "
      "<button id=\"fwd\">&gt;</button> speed <select id=\"speed\"><option>1</option><option "
      "selected>2</option><option>5</option><option>20</option></select> <input id=\"t\" "
      "type=\"range\" min=\"0\" value=\"0\"> <label><input id=\"goals\" type=\"checkbox\"> "
      "lines to goals</label> <span id=\"lbl\"></span><br><small>robots as discs (number = "
      "robot; dark rim: to its pickup, white rim: to its drop-off, thick black rim: dwelling); "
      "solid: released base, dashed: horizon</small></div>\n<div id=\"stage\">";
  html += siteSvg(site, roadmap);
  html += "<svg id=\"ov\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" + std::to_string(f.pageW) +
          "\" height=\"" + std::to_string(f.pageH) + "\" viewBox=\"0 0 " + std::to_string(f.pageW) + " " +
          std::to_string(f.pageH) +
          "\"></svg></div>\n<script>document.getElementById('stage').style.height = '" +
          std::to_string(f.pageH) + "px';\nconst DATA = ";
  html += json;
  html += ";\n";
  html += kScript;
  html += "</script></body></html>\n";
  return html;
}

}  // namespace fleet::ctl
