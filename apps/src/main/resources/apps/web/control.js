// The web view's control panel (docs/web.md, "The control panel"): shown only when the gateway offers it. Keys, touch
// and the Gamepad API become walk commands for the chosen robot, sent five times a second while held (the gateway
// stops a robot whose commands stop), and one stop when let go.
"use strict";
(function () {
  const token = new URLSearchParams(location.search).get("token");
  const panel = document.getElementById("control");
  const select = document.getElementById("control-robot");
  const result = document.getElementById("control-result");
  const KEYS = { w: [0.2, 0, 0], s: [-0.1, 0, 0], a: [0, 0, 0.6], d: [0, 0, -0.6], q: [0, 0.1, 0], e: [0, -0.1, 0],
    ArrowUp: [0.2, 0, 0], ArrowDown: [-0.1, 0, 0], ArrowLeft: [0, 0, 0.6], ArrowRight: [0, 0, -0.6] };
  const held = new Map(); // source (key, pointer, gamepad) -> [vx, vy, omega]
  const control = window.naogatewayControl = { sent: 0, results: [] };
  let ws = null;
  let moving = false;

  function send(op, v) {
    if (!ws || ws.readyState !== WebSocket.OPEN || select.value === "") return;
    const request = { op: op, robot: Number(select.value) };
    if (v) { request.vx = v[0]; request.vy = v[1]; request.omega = v[2]; }
    ws.send(JSON.stringify(request));
    control.sent++;
  }

  // What the held inputs add up to; sent while anything is held, then one stop.
  function tick() {
    const v = [0, 0, 0];
    held.forEach(h => { v[0] += h[0]; v[1] += h[1]; v[2] += h[2]; });
    if (held.size > 0) { send("walk", v); moving = true; }
    else if (moving) { send("stop"); moving = false; }
  }

  function pollGamepad() {
    const pads = navigator.getGamepads ? Array.from(navigator.getGamepads()).filter(p => p && p.connected) : [];
    const pad = pads[0];
    const dead = x => (Math.abs(x) < 0.15 ? 0 : x);
    if (pad && pad.axes.length >= 2 && (dead(pad.axes[0]) !== 0 || dead(pad.axes[1]) !== 0 || dead(pad.axes[2] || 0) !== 0)) {
      // Left stick: forward/back and turn; right stick x: sideways.
      held.set("gamepad", [-dead(pad.axes[1]) * 0.2, -dead(pad.axes[2] || 0) * 0.1, -dead(pad.axes[0]) * 0.6]);
    } else held.delete("gamepad");
  }

  function start() {
    panel.hidden = false;
    ws = new WebSocket((location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/control" +
      (token ? "?token=" + encodeURIComponent(token) : ""));
    ws.onmessage = e => {
      const r = JSON.parse(e.data);
      control.results.push(r);
      if (control.results.length > 20) control.results.shift();
      result.textContent = r.message;
      result.className = "small " + (r.ok ? "good" : "bad");
    };
    ws.onclose = () => { result.textContent = "control disconnected, retrying"; setTimeout(start, 2000); };
    document.addEventListener("keydown", e => {
      if (e.key === " ") { held.clear(); send("stop"); moving = false; e.preventDefault(); return; }
      const v = KEYS[e.key] || KEYS[e.key.toLowerCase()];
      if (v && e.target.tagName !== "SELECT") { held.set("key:" + e.key.toLowerCase(), v); e.preventDefault(); }
    });
    document.addEventListener("keyup", e => held.delete("key:" + e.key.toLowerCase()));
    panel.querySelectorAll("button[data-drive]").forEach(b => {
      const v = b.dataset.drive.split(",").map(Number);
      b.addEventListener("pointerdown", e => { held.set("pointer", v); e.preventDefault(); });
      ["pointerup", "pointerleave", "pointercancel"].forEach(t => b.addEventListener(t, () => held.delete("pointer")));
    });
    setInterval(() => { pollGamepad(); tick(); }, 200);
    // The robots to choose from: those the page shows.
    setInterval(() => {
      const ids = Array.from(document.querySelectorAll("#robots .robot")).map(r => r.dataset.robot);
      const have = Array.from(select.options).map(o => o.value);
      ids.filter(id => !have.includes(id)).forEach(id => select.add(new Option("robot " + id, id)));
    }, 1000);
  }

  fetch("control/state").then(r => r.json()).then(s => { if (s.enabled) start(); }).catch(() => {});
})();
