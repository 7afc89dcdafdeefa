// The web view's page (docs/web.md): reads the gateway's pushes from the WebSocket /ws and draws them.
// The state it keeps is bounded: each plot holds at most the gateway's history-points, the log its events.
"use strict";
(function () {
  const token = new URLSearchParams(location.search).get("token");
  const wsUrl = (location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/ws" +
    (token ? "?token=" + encodeURIComponent(token) : "");

  // HaViMo2 colour classes as the demo's scene uses them (1 ball, 2 yellow goal, 3 blue goal), then field, lines.
  const COLOURS = ["#000000", "#ff8c1a", "#f5e050", "#3a78ff", "#2f9e44", "#ffffff", "#c92a2a", "#be4bdb",
    "#15aabf", "#868e96", "#fab005", "#82c91e", "#e64980", "#4c6ef5", "#12b886", "#ced4da"];

  // What the tests and the curious can read: pushes seen, the game state shown, points on the traffic plot.
  // `changes`: the last game-state changes with the page's clock when it showed them (the bench's latency figure).
  // `servoRows`: rows of each robot's servo table shown.
  const status = window.naogateway = { pushes: 0, gameState: null, trafficPoints: 0, robotsOnline: 0, lastPushAt: 0, changes: [], servoRows: {} };
  let historyPoints = 180;
  const robots = new Map(); // id -> { el, plots, data }
  const traffic = { data: [[], [], [], []], plot: null };
  const eventsList = document.getElementById("events");

  function text(el, value) { el.textContent = value == null ? "-" : String(value); }
  function fixed(v, digits, unit) { return v == null ? "-" : v.toFixed(digits) + (unit ? " " + unit : ""); }
  function clock(wall) { return new Date(wall).toLocaleTimeString([], { hour12: false }); }

  // A small plot of `series` over the seconds since the gateway's view started; `share` of the parent's width.
  function plot(el, title, series, height, share) {
    const width = Math.max(100, Math.floor((el.parentElement.clientWidth || 320) * (share || 1)) - 12);
    const opts = {
      title: title, width: width, height: height || 90, legend: { show: false }, cursor: { show: false },
      scales: { x: { time: false } }, axes: [{ show: false }, { size: 54, stroke: "#aab3bd", grid: { stroke: "#2c323a" } }],
      series: [{}].concat(series.map(s => ({ label: s.label, stroke: s.stroke, width: 1.5, spanGaps: true, points: { show: false } })))
    };
    return new uPlot(opts, [[]].concat(series.map(() => [])), el);
  }

  // Appends points to a plot's columns, keeping at most historyPoints of them.
  function append(data, rows) {
    rows.forEach(r => r.forEach((v, i) => data[i].push(v)));
    const extra = data[0].length - historyPoints;
    if (extra > 0) data.forEach(col => col.splice(0, extra));
  }

  function robotCard(id) {
    let r = robots.get(id);
    if (r) return r;
    const el = document.getElementById("robot-template").content.firstElementChild.cloneNode(true);
    el.id = "robot-" + id;
    el.dataset.robot = id;
    document.getElementById("robots").appendChild(el);
    const q = c => el.querySelector(c);
    r = {
      el: el, q: q, data: [[], [], [], []],
      plots: {
        battery: plot(q(".robot-plot-battery"), "battery (V)", [{ label: "battery", stroke: "#5fd068" }], 90, 1 / 3),
        rtt: plot(q(".robot-plot-rtt"), "rtt (ms)", [{ label: "rtt", stroke: "#4dabf7" }], 90, 1 / 3),
        loss: plot(q(".robot-plot-loss"), "loss (%)", [{ label: "loss", stroke: "#ff8787" }], 90, 1 / 3)
      }
    };
    robots.set(id, r);
    return r;
  }

  function showRobot(robot) {
    const r = robotCard(robot.id);
    const q = r.q;
    text(q(".robot-name"), "robot " + robot.id);
    const online = q(".robot-online");
    text(online, robot.online ? "online" + (robot.quality && robot.quality !== "good" ? " (" + robot.quality + ")" : "") : "offline");
    online.className = "robot-online " + (robot.online ? (robot.quality === "good" ? "good" : "warn") : "bad");
    const trend = r.data[1].filter(v => v != null);
    const slope = trend.length > 10 ? trend[trend.length - 1] - trend[trend.length - 11] : 0;
    text(q(".robot-battery"), fixed(robot.battery, 2, "V") + (slope < -0.005 ? " ↘" : slope > 0.005 ? " ↗" : ""));
    text(q(".robot-posture"), robot.posture);
    text(q(".robot-role"), robot.role);
    text(q(".robot-rtt"), fixed(robot.rttMs, 1, "ms"));
    text(q(".robot-loss"), robot.loss == null ? "-" : (robot.loss * 100).toFixed(0) + " %");
    const c = robot.clock;
    const drift = c && (c.driftSettled ? c.driftPpm.toFixed(0) + " ± " + c.driftBoundPpm.toFixed(0) + " ppm" : "drift settling");
    text(q(".robot-clock"), c ? drift + ", offset ± " + fixed(c.errorBoundMs, 1, "ms") + " (" + c.samples + " samples)" : "-");
    text(q(".robot-signing"), (robot.signing || "-") + (robot.development ? ", development build" : ""));
    const p = robot.penalty;
    text(q(".robot-penalty"), p ? "PENALISED: " + p.name + (p.secondsLeft > 0 ? ", " + p.secondsLeft + " s left" : "") : "");
    text(q(".robot-address"), robot.address);
    const refused = Object.entries(robot.refused || {}).map(([k, v]) => k + " " + v).join(", ");
    text(q(".robot-refused"), refused ? "refused: " + refused : "");
    showServos(q(".robot-servos"), robot.id, robot.servos);
  }

  // The robot's servo table (docs/web.md): one row per servo; silent ones greyed, hot or low-voltage figures marked.
  function showServos(table, id, servos) {
    table.hidden = !servos;
    const body = table.querySelector("tbody");
    if (!servos) { body.replaceChildren(); status.servoRows[id] = 0; return; }
    text(table.querySelector(".robot-servo-errors"), servos.busErrors ? servos.busErrors + " bus errors" : "");
    body.replaceChildren(...servos.list.map(s => {
      const tr = document.createElement("tr");
      tr.dataset.servo = s.id;
      if (s.silent) tr.className = "silent";
      const cells = s.silent ? [s.id, "silent", "", "", ""] : [
        s.id,
        s.position == null ? "-" : s.position + (s.degrees == null ? "" : " (" + s.degrees.toFixed(0) + "°)"),
        s.load == null ? "-" : s.load,
        fixed(s.voltage, 1, "V"),
        s.temperature == null ? "-" : s.temperature + " °C"];
      cells.forEach((v, i) => {
        const td = document.createElement("td");
        td.textContent = String(v);
        if (i === 3 && s.lowVoltage) { td.className = "bad low-voltage"; td.title = "low voltage"; }
        if (i === 4 && s.hot) { td.className = "bad hot"; td.title = "hot"; }
        tr.appendChild(td);
      });
      return tr;
    }));
    status.servoRows[id] = servos.list.length;
  }

  // Draws a frame as FU-Remote does: the grid's cells in their colour class (brighter with more pixels), then each
  // region's bounding box in its colour with a cross at its centre of mass, at the camera's 160 × 120 pixels.
  function drawVision(id, v) {
    const r = robots.get(Number(id));
    if (!r) return;
    if (v.grid) r.grid = Uint8Array.from(atob(v.grid), c => c.charCodeAt(0));
    const ctx = r.q(".robot-vision").getContext("2d");
    ctx.fillStyle = "#000";
    ctx.fillRect(0, 0, 160, 120);
    if (r.grid && r.grid.length === 768) {
      for (let i = 0; i < 768; i++) {
        const colour = r.grid[i] & 0x0f, count = r.grid[i] >> 4;
        if (colour === 0) continue;
        ctx.globalAlpha = 0.25 + 0.5 * count / 15;
        ctx.fillStyle = COLOURS[colour];
        ctx.fillRect((i % 32) * 5, Math.floor(i / 32) * 5, 5, 5);
      }
      ctx.globalAlpha = 1;
    }
    ctx.lineWidth = 1;
    (v.regions || []).forEach(g => {
      ctx.strokeStyle = COLOURS[g.colour & 0x0f];
      ctx.strokeRect(g.minX + 0.5, g.minY + 0.5, Math.max(g.maxX - g.minX, 1), Math.max(g.maxY - g.minY, 1));
      ctx.beginPath();
      ctx.moveTo(g.cx - 3, g.cy); ctx.lineTo(g.cx + 3, g.cy);
      ctx.moveTo(g.cx, g.cy - 3); ctx.lineTo(g.cx, g.cy + 3);
      ctx.stroke();
    });
  }

  function showGame(g) {
    text(document.getElementById("game-state"), g.state);
    text(document.getElementById("game-secondary"), g.secondary && g.secondary !== "NORMAL" ? "(" + g.secondary.toLowerCase() + ")" : "");
    text(document.getElementById("game-time"), g.secsRemaining == null ? null :
      (g.firstHalf ? "1st" : "2nd") + " half, " + g.secsRemaining + " s left" + (g.secondaryTime ? ", secondary " + g.secondaryTime + " s" : ""));
    text(document.getElementById("game-score"), g.teams ? g.teams.map(t => t.score + " (team " + t.team + ")").join(" : ") : null);
    text(document.getElementById("game-version"), g.version == null ? "none heard" : "version " + g.version);
    text(document.getElementById("game-source"), g.source);
    const gate = document.getElementById("game-gate");
    text(gate, g.gate);
    gate.className = g.gate === "closed" ? "bad" : "good";
    const t = g.traffic;
    text(document.getElementById("game-traffic"), t ? "out " + (t.outBytes / 1000).toFixed(1) + " kB/s, in " + (t.inBytes / 1000).toFixed(1) +
      " kB/s of " + (t.budget / 1000).toFixed(1) + " kB/s" + (t.refusedByRule ? ", " + t.refusedByRule + " refused by rule" : "") +
      (t.dropped ? ", " + t.dropped + " dropped" : "") : null);
    const refused = Object.entries(g.refused || {}).map(([k, v]) => k + " " + v).join(", ");
    text(document.getElementById("gateway-refused"), refused ? "gateway refused: " + refused : "");
    if (g.state !== status.gameState) {
      status.changes.push({ state: g.state, at: Date.now() });
      if (status.changes.length > 50) status.changes.shift();
    }
    status.gameState = g.state;
  }

  function showEvents(events, hello) {
    if (hello) eventsList.replaceChildren();
    // Oldest of the new first, so each goes on top and the newest ends first.
    events.slice().reverse().forEach(e => {
      const li = document.createElement("li");
      li.className = "event-" + e.kind + (e.kind === "offline" || e.kind === "refusal" ? " bad" : "");
      const time = document.createElement("span");
      time.className = "time";
      time.textContent = clock(e.wall);
      li.append(time, e.text);
      eventsList.prepend(li);
    });
    while (eventsList.children.length > 200) eventsList.lastElementChild.remove();
  }

  function onPush(m) {
    const hello = m.type === "hello";
    historyPoints = m.historyPoints || historyPoints;
    if (hello) {
      robots.forEach(r => { r.data = [[], [], [], []]; });
      traffic.data = [[], [], [], []];
    }
    m.robots.forEach(showRobot);
    robots.forEach((r, id) => { if (!m.robots.some(x => x.id === id)) { r.el.remove(); robots.delete(id); } });
    Object.entries(m.samples.robots).forEach(([id, rows]) => {
      const r = robots.get(Number(id));
      if (!r || rows.length === 0) return;
      append(r.data, rows.map(p => [p[0], p[1], p[2], p[3] == null ? null : p[3] * 100]));
      r.plots.battery.setData([r.data[0], r.data[1]]);
      r.plots.rtt.setData([r.data[0], r.data[2]]);
      r.plots.loss.setData([r.data[0], r.data[3]]);
    });
    if (m.samples.traffic.length > 0) {
      append(traffic.data, m.samples.traffic.map(p => [p[0], p[1] / 1000, p[2] / 1000, p[3] / 1000]));
      traffic.plot.setData(traffic.data);
      status.trafficPoints = traffic.data[0].length;
    }
    Object.entries(m.vision).forEach(([id, v]) => drawVision(id, v));
    showGame(m.game);
    showEvents(m.events, hello);
    status.robotsOnline = m.robots.filter(r => r.online).length;
    status.pushes++;
    status.lastPushAt = Date.now();
  }

  function connect() {
    const ws = new WebSocket(wsUrl);
    const shown = document.getElementById("connection");
    ws.onopen = () => { shown.textContent = "live"; shown.className = "good"; };
    ws.onmessage = e => onPush(JSON.parse(e.data));
    ws.onclose = () => {
      shown.textContent = "disconnected, retrying";
      shown.className = "bad";
      setTimeout(connect, 2000);
    };
  }

  traffic.plot = plot(document.getElementById("traffic-plot"), "team traffic (kB/s) against the budget", [
    { label: "out", stroke: "#4dabf7" }, { label: "in", stroke: "#5fd068" }, { label: "budget", stroke: "#ff6a5c" }], 140);
  connect();
})();
