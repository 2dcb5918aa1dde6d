// SPDX-License-Identifier: MIT
// Glue of the torqueloop dashboard (torqueloop/host/dash/web.py serves it):
// rows from the WebSocket into the BokehJS sources, the controls into requests.
// BokehJS draws; window.tl holds the page's counters (tests and the bench read them).
"use strict";
const tl = window.tl = {cfg: null, rows: [], pending: [], held: [], lastSeq: null, paused: false, unit: "mm",
  received: 0, gaps: 0, dropped: 0, lat: [], ws: null, id: 0, waiting: {}, us0: null, usLast: null, usWrap: 0,
  status: null, replies: [], cmdLimit: [NaN, NaN]};
const KEEP_ROWS = 60000, KEEP_LAT = 20000, ROLLOVER = 20000;
const MIN_DRAW_MS = 50;                   // at most 20 redraws a second: a busy machine keeps up
const $ = (id) => document.getElementById(id);

function log(text, bad) {
  const line = document.createElement("div");
  line.textContent = new Date().toLocaleTimeString() + "  " + text;
  if (bad) line.className = "err";
  $("log").prepend(line);
}

function request(op, params) {
  const id = ++tl.id;
  return new Promise((resolve) => {
    tl.waiting[id] = resolve;
    tl.ws.send(JSON.stringify({id, op, params: params || {}}));
  }).then((rep) => {
    tl.replies.push(rep);
    if (!rep.ok) log(op + ": " + rep.error, true);
    else if (typeof rep.result === "string") log(rep.result);
    return rep;
  });
}

// ---- telemetry -------------------------------------------------------------
function tOf(row) {                       // board time in s, time_us unwrapped (u32)
  const us = row[tl.ix.time_us];
  if (tl.us0 === null) tl.us0 = us;
  if (tl.usLast !== null && us < tl.usLast) tl.usWrap += 4294967296;
  tl.usLast = us;
  return (us + tl.usWrap - tl.us0) / 1e6;
}

function take(rows) {
  for (const r of rows) {
    if (tl.lastSeq !== null && r[0] <= tl.lastSeq) continue;            // already have it (a replay)
    if (tl.lastSeq !== null && r[0] > tl.lastSeq + 1) tl.gaps += r[0] - tl.lastSeq - 1;
    tl.lastSeq = r[0];
    tl.received++;
    const item = [tOf(r), r];
    tl.rows.push(item);
    tl.pending.push(item);
  }
  if (tl.rows.length > KEEP_ROWS) tl.rows.splice(0, tl.rows.length - KEEP_ROWS);
  if (!tl.frame) tl.frame = requestAnimationFrame(draw);
}

function columns(items, a) {
  const ix = tl.ix, sc = tl.cfg.scales[a][tl.unit], out = {};
  for (const c of tl.cfg.columns) out[c] = [];
  for (const [t, r] of items) {
    out.t.push(t);
    out.setpoint.push(r[ix["setpoint" + a]] * sc);
    out.position.push(r[ix["position" + a]] * sc);
    out.error.push(r[ix["error" + a]] * sc);
    out.pwm_cmd.push(r[ix["pwm_cmd" + a]]);
    out.limit_hi.push(tl.cmdLimit[a]);
    out.limit_lo.push(-tl.cmdLimit[a]);
    out.velocity.push(r[ix["velocity_q8" + a]] / 256 * sc);
    for (const c of tl.cfg.columns) if (c.startsWith("current")) out[c].push(r[ix[c + a]]);
  }
  return out;
}

function draw(now) {
  if (now - (tl.lastDraw || 0) < MIN_DRAW_MS) { tl.frame = requestAnimationFrame(draw); return; }
  tl.lastDraw = now;
  tl.frame = null;
  const items = tl.pending;
  tl.pending = [];
  if (tl.paused) { tl.held.push(...items); return; }
  if (!items.length) return;
  for (let a = 0; a < tl.cfg.axes; a++) tl.src[a].stream(columns(items, a), ROLLOVER);
  // the next frame is drawn with these rows in it: the latency of each, from the server's reading it
  requestAnimationFrame(() => {
    const now = performance.timeOrigin + performance.now();
    for (const [, r] of items) tl.lat.push(now - r[1]);
    if (tl.lat.length > KEEP_LAT) tl.lat.splice(0, tl.lat.length - KEEP_LAT);
  });
  $("counts").textContent = `${tl.received} records, ${tl.gaps + tl.dropped} dropped`;
}

function refill() {                       // the whole view again (a new unit)
  for (let a = 0; a < tl.cfg.axes; a++) tl.src[a].data = columns(tl.rows.slice(-ROLLOVER), a);
}

// ---- the connection ---------------------------------------------------------
function connect() {
  const proto = location.protocol === "https:" ? "wss:" : "ws:";
  const ws = tl.ws = new WebSocket(`${proto}//${location.host}/ws?since=${tl.lastSeq === null ? "" : tl.lastSeq}`);
  ws.onopen = () => { $("link").textContent = "connected"; };
  ws.onclose = () => {
    $("link").textContent = "disconnected: reconnecting...";
    for (const id in tl.waiting) tl.waiting[id]({ok: false, error: "connection lost"});
    tl.waiting = {};
    setTimeout(connect, 1000);
  };
  ws.onmessage = (ev) => {
    const m = JSON.parse(ev.data);
    if (m.t === "rows") { tl.dropped = m.dropped; take(m.rows); }
    else if (m.t === "hello") { tl.role = m.role; tl.gaps += m.lost; take(m.rows); setRole(m.role); }
    else if (m.t === "status") showStatus(m);
    else if (m.t === "reply" && tl.waiting[m.id]) { tl.waiting[m.id](m); delete tl.waiting[m.id]; }
  };
}

// ---- controls ---------------------------------------------------------------
function el(tag, attrs, text) {
  const e = document.createElement(tag);
  Object.assign(e, attrs || {});
  if (text !== undefined) e.textContent = text;
  return e;
}

function unitSelect(sel) {
  const s = el("select");
  for (const u of tl.cfg.units) s.append(el("option", {value: u, selected: u === sel}, u));
  return s;
}

function axisPanel(a) {
  const box = el("div", {className: "axis", id: "axis" + a});
  box.append(el("h3", {}, `axis ${a}`), el("div", {className: "state", id: "state" + a}, "..."));
  const btn = (label, op, params, title) => {
    const b = el("button", {className: "cmd", title: title || ""}, label);
    b.onclick = () => request(op, typeof params === "function" ? params() : params);
    return b;
  };
  const r1 = el("div", {className: "row"});
  r1.append(btn("enable", "enable", {axis: a, on: true}), btn("disable", "enable", {axis: a, on: false}),
    btn("clear fault", "clear_fault", {axis: a}), btn("home here", "home", {axis: a, mode: "here"},
    "the present position becomes HOME_POS (no switches)"), btn("home neg", "home", {axis: a, mode: "neg"}));
  const tgt = el("input", {type: "text", value: "2", id: "target" + a}), tu = unitSelect("mm");
  tu.id = "tunit" + a;
  const rel = el("input", {type: "checkbox", id: "rel" + a, checked: true});
  const trap = el("input", {type: "checkbox", id: "trap" + a});
  const unh = el("input", {type: "checkbox", id: "unhomed" + a, checked: true});
  const mv = btn("move", "move", () => ({axis: a, target: tgt.value, unit: tu.value, relative: rel.checked,
    trapezoid: trap.checked, unhomed: unh.checked}), "enables the axis if needed");
  mv.id = "move" + a;
  const r2 = el("div", {className: "row"});
  r2.append("move ", tgt, tu, mv, " ", rel, "relative ", trap, "trapezoid ", unh, "unhomed");
  const duty = el("input", {type: "text", value: "5%", id: "duty" + a});
  const secs = el("input", {type: "text", value: "1", id: "secs" + a});
  const r3 = el("div", {className: "row"});
  r3.append("open loop ", duty, " for ", secs, " s ", btn("drive", "drive", () => ({axis: a, duty: duty.value,
    seconds: secs.value}), "open-loop PWM command, every safety check on; disabled at the end"));
  const st = el("input", {type: "text", value: "1", id: "step" + a}), su = unitSelect("mm");
  const dur = el("input", {type: "text", value: "3", id: "stepdur" + a});
  const fig = el("span", {id: "figs" + a});
  const sb = el("button", {className: "cmd", id: "stepbtn" + a}, "step test");
  sb.onclick = () => {
    fig.textContent = "stepping...";
    request("step", {axis: a, target: st.value, unit: su.value, duration: dur.value}).then((rep) => {
      if (!rep.ok) { fig.textContent = ""; return; }
      const f = rep.result, u = f.unit, n = (v, d) => v === null ? "-" : v.toFixed(d);
      fig.textContent = `overshoot ${n(f.overshoot_pct, 1)} %, rise ${n(f.rise_time_s, 3)} s, settling ` +
        `${n(f.settling_time_s, 3)} s, RMSE ${n(f["rmse_" + u] ?? f.rmse_counts, 4)} ${u}`;
    });
  };
  const r4 = el("div", {className: "row"});
  r4.append("step ", st, su, " for ", dur, " s ", sb, " ", fig);
  box.append(r1, r2, r3, r4);
  return box;
}

function setRole(role) {
  $("role").textContent = role === "command" ? "(command)" : "(watching: STOP only)";
  for (const b of document.querySelectorAll(".cmd")) b.disabled = role !== "command";
}

function showStatus(m) {
  tl.status = m;
  if (m.error) { $("link").textContent = "board: " + m.error; return; }
  m.axes.forEach((s, a) => {
    const e = $("state" + a);
    const held = (m.holds[String(a)] || []).length ? `, held by ${m.holds[String(a)].length}` : "";
    e.textContent = `${s.enabled ? "ENABLED" : "disabled"}${s.moving ? ", moving" : ""}, ${s.home}${held}; ` +
      `faults: ${s.fault_words}`;
    e.className = "state" + (s.faults.length ? " fault" : "");
    tl.cmdLimit[a] = s.cmd_limit;
  });
  $("link").textContent = `connected, ${m.pages} page(s)`;
  tl.dropped = m.dropped;
}

async function params() {
  const a = Number($("paxis").value);
  const rep = await request("params", {axis: a});
  if (!rep.ok) return;
  const body = $("ptable");
  body.textContent = "";
  for (const p of rep.result) {
    const tr = el("tr");
    const inp = el("input", {type: "text", value: String(p.value)});
    const set = el("button", {className: "cmd"}, "set");
    set.onclick = () => request("set_param", {axis: a, name: p.name, value: inp.value}).then(params);
    tr.append(el("td", {}, p.name + (p.global ? " (both axes)" : "")), el("td", {}, `${p.value} ${p.unit}`),
      el("td", {}, p.range), el("td", {}, ""), el("td", {}, ""), el("td", {}, p.help));
    tr.children[3].append(inp);
    tr.children[4].append(set);
    body.append(tr);
  }
  setRole(tl.role);
}

function csv() {
  const lo = tl.xr.start, hi = tl.xr.end;
  const lines = [["t_s", ...tl.cfg.row].join(",")];
  for (const [t, r] of tl.rows) if (t >= lo && t <= hi) lines.push([t.toFixed(6), ...r].join(","));
  const a = el("a", {href: URL.createObjectURL(new Blob([lines.join("\n") + "\n"], {type: "text/csv"})),
    download: "torqueloop-view.csv"});
  document.body.append(a);
  a.click();
  a.remove();
  return lines.length - 1;
}

async function main() {
  const r = await fetch("/api/config");
  if (!r.ok) { $("link").textContent = "refused: " + (await r.text()); return; }
  const cfg = tl.cfg = await r.json();
  tl.ix = Object.fromEntries(cfg.row.map((n, i) => [n, i]));
  $("board").textContent = cfg.board;
  for (let a = 0; a < cfg.axes; a++) {
    $("axes").append(axisPanel(a));
    $("paxis").append(el("option", {value: a}, `axis ${a}`));
  }
  for (const u of cfg.units) $("unit").append(el("option", {value: u, selected: u === tl.unit}, u));
  $("unit").onchange = () => { tl.unit = $("unit").value; refill(); };
  $("stop").onclick = () => request("stop");
  $("pget").onclick = params;
  $("psave").onclick = () => request("save");
  $("csv").onclick = csv;
  $("pause").onclick = () => {
    tl.paused = !tl.paused;
    $("pause").textContent = tl.paused ? "resume" : "pause";
    $("csv").disabled = !tl.paused;
    if (tl.paused) tl.xr.follow = null;
    else {
      tl.xr.follow = "end";
      tl.xr.reset();
      tl.pending = tl.held.concat(tl.pending);
      tl.held = [];
      if (!tl.frame) tl.frame = requestAnimationFrame(draw);
    }
  };
  await Bokeh.embed.embed_item(cfg.plots, "plots");
  tl.doc = Bokeh.documents[Bokeh.documents.length - 1];
  tl.src = [...Array(cfg.axes).keys()].map((a) => tl.doc.get_model_by_name("ax" + a));
  tl.xr = tl.doc.get_model_by_name("x_range");
  connect();
  tl.ready = true;
}
main();
