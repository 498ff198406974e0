"use strict";
(function () {
  const REFRESH_MS = Number(document.body.dataset.refreshMs) || 1000;
  const TIMEOUT_MS = 2500;      // a request that hangs longer counts as unreachable
  const STALE_MS = 3000;        // drive data older than this is greyed out
  const NEVER = 4294967295;     // data_age_ms of a drive never heard from
  const COUNTERS = [["frames_good", "frames good"], ["bad_checksum", "bad checksum"],
    ["timeouts", "timeouts"], ["retries", "retries"], ["nacks", "nacks"],
    ["foreign_frames", "foreign"]];
  const $ = (id) => document.getElementById(id);
  const cards = new Map();      // device name -> {el, f: {field: element}, pointNames}
  const busRows = new Map();
  const lisRows = new Map();
  const prevBusy = new Map();   // bus name -> {busy, now}: line utilisation between two polls
  let lastGood = null;          // daemon's `now` and local time of the last good answer
  let failingSince = null;     // {at: local ms, reason} while the daemon does not answer
  let updates = 0;

  function el(tag, attrs, text) {
    const e = document.createElement(tag);
    if (attrs) for (const k in attrs) e.setAttribute(k, attrs[k]);
    if (text !== undefined) e.textContent = text;
    return e;
  }
  function set(e, text) {
    text = String(text);
    if (e.textContent !== text) e.textContent = text;
  }
  function num(v) {
    return typeof v === "number" ? v.toLocaleString("en-US") : (v === null || v === undefined ? "-" : String(v));
  }
  function hex(v, digits) {
    return typeof v === "number" ? "0x" + (v >>> 0).toString(16).toUpperCase().padStart(digits, "0") : "-";
  }
  function age(ms) {
    if (ms === undefined || ms === null) return "-";
    if (ms >= NEVER) return "never";
    if (ms < 1000) return Math.round(ms) + " ms";
    if (ms < 60000) return (ms / 1000).toFixed(1) + " s";
    if (ms < 3600000) return Math.floor(ms / 60000) + " min " + Math.floor(ms % 60000 / 1000) + " s";
    return Math.floor(ms / 3600000) + " h " + Math.floor(ms % 3600000 / 60000) + " min";
  }
  function clock(unix) {
    const d = new Date(unix * 1000);
    return [d.getHours(), d.getMinutes(), d.getSeconds()].map((x) => String(x).padStart(2, "0")).join(":");
  }
  function duration(s) {
    s = Math.max(0, Math.floor(s));
    const d = Math.floor(s / 86400), h = Math.floor(s % 86400 / 3600), m = Math.floor(s % 3600 / 60);
    if (d) return d + "d " + h + "h";
    if (h) return h + "h " + m + "m";
    return m + "m " + (s % 60) + "s";
  }

  function makeCard(d) {
    const f = {};
    const field = (tag, name, attrs, text) => {
      const e = el(tag, Object.assign({"data-field": name}, attrs || {}), text);
      f[name] = e;
      return e;
    };
    const card = el("article", {"class": "card", "data-device": d.name});
    const head = el("div", {"class": "head"});
    head.append(field("h3", "name", null, d.name), field("span", "state", {"class": "state"}));
    const sub = el("div", {"class": "sub"});
    sub.append(field("b", "adapter"), " \u00b7 unit ", field("b", "unit"), " \u00b7 bus ", field("b", "bus"));
    const comm = field("div", "comm_banner", {"class": "commlost"});
    const badges = field("div", "status_bits", {"class": "badges"});
    const values = el("div", {"class": "values"});
    const speed = el("div", {"class": "speed"});
    const sp = el("span", {"class": "sp"});
    sp.append("setpoint ", field("b", "setpoint_rpm"), " rpm");
    speed.append(field("span", "speed_rpm", {"class": "big"}), el("span", {"class": "unit"}, "rpm"), sp);
    const bar = el("div", {"class": "bar"});
    f.fill = el("i", {"class": "fill"});
    f.mark = el("i", {"class": "mark"});
    bar.append(f.fill, f.mark);
    const kv = el("dl", {"class": "kv"});
    const row = (label, name) => kv.append(el("dt", null, label), field("dd", name));
    const faultDd = el("dd", {"class": "keep"});
    const faultBox = el("span");
    faultBox.append(field("span", "fault_label"), " ", field("span", "fault_code"));
    faultDd.append(faultBox);
    f.fault = faultBox;
    kv.append(el("dt", null, "Fault"), faultDd);
    const pair = (label, a, label2, b) => {
      const dd = el("dd");
      dd.append(field("span", a), el("span", {"class": "k2"}, label2), field("span", b));
      kv.append(el("dt", null, label), dd);
    };
    pair("Native fault", "native_fault", "mask", "fault_mask");
    row("Data age", "data_age_ms");
    row("Failsafe", "failsafe");
    pair("Command", "command", "heartbeat", "heartbeat");
    const counters = el("div", {"class": "counters"});
    for (const [key, label] of COUNTERS) {
      const c = el("div");
      c.append(el("span", null, label), field("b", key));
      counters.append(c);
    }
    values.append(speed, bar, kv, counters);
    const det = el("details");
    f.points_summary = el("summary", null, "drive points");
    f.points = field("tbody", "points");
    const pt = el("table");
    pt.append(f.points);
    det.append(f.points_summary, pt);
    card.append(head, sub, comm, badges, values, det);
    return {el: card, f: f, pointNames: ""};
  }

  function deviceState(d) {
    const bits = d.status_bits || [];
    const c = d.common || {};
    if (d.comm_lost) return ["comm_lost", "COMM LOST"];
    if (bits.includes("fault") || (c.fault_code || 0) !== 0) return ["fault", "FAULT"];
    if (d.failsafe_latched) return ["failsafe", "FAILSAFE"];
    if (!d.online) return ["offline", "OFFLINE"];
    if (bits.includes("warning")) return ["warning", "WARNING"];
    if (bits.includes("running")) return ["running", "RUNNING"];
    return ["stopped", "STOPPED"];
  }

  function renderDevice(card, d) {
    const f = card.f, c = d.common || {}, labels = d.labels || {};
    const [state, stateText] = deviceState(d);
    const ageMs = c.data_age_ms;
    const stale = d.comm_lost || ageMs === undefined || ageMs >= NEVER || ageMs > STALE_MS;
    card.el.dataset.state = state;
    card.el.dataset.fault = labels.fault_code || (c.fault_code ? String(c.fault_code) : "none");
    card.el.classList.toggle("stale", stale);
    set(f.state, stateText);
    set(f.adapter, d.adapter);
    set(f.unit, d.unit);
    set(f.bus, d.bus);
    f.comm_banner.hidden = !d.comm_lost;
    set(f.comm_banner, "COMMUNICATION LOST \u2014 values are " + (ageMs >= NEVER ? "missing (never heard)" : age(ageMs) + " old"));
    const bits = (d.status_bits || []).join(" ");
    if (f.status_bits.dataset.bits !== bits || !f.status_bits.firstChild) {
      f.status_bits.dataset.bits = bits;
      f.status_bits.replaceChildren();
      for (const b of d.status_bits || []) f.status_bits.append(el("span", {"class": "badge", "data-bit": b}, b));
      if (!(d.status_bits || []).length) f.status_bits.append(el("span", {"class": "badge none"}, "no status bits set"));
    }
    set(f.speed_rpm, c.speed_rpm === undefined || c.speed_rpm === null ? "-" : c.speed_rpm);
    f.speed_rpm.dataset.value = c.speed_rpm;
    set(f.setpoint_rpm, c.setpoint_rpm === undefined ? "-" : c.setpoint_rpm);
    set(f.command, labels.command || (c.command === undefined ? "-" : c.command));
    const speed = Math.abs(Number(c.speed_rpm) || 0), setpoint = Math.abs(Number(c.setpoint_rpm) || 0);
    const scale = Math.max(speed, setpoint) * 1.15 || 1;
    f.fill.style.width = (100 * speed / scale).toFixed(1) + "%";
    f.mark.style.display = setpoint ? "block" : "none";
    f.mark.style.left = (100 * setpoint / scale).toFixed(1) + "%";
    const code = c.fault_code || 0;
    set(f.fault_label, labels.fault_code || (code ? "fault" : "none"));
    set(f.fault_code, "(" + (c.fault_code === undefined ? "-" : c.fault_code) + ")");
    f.fault_code.dataset.value = code;
    f.fault.className = code ? (d.comm_lost || code === 1 ? "alarmfield comm" : "alarmfield") : "";
    set(f.native_fault, hex(c.native_fault, 4));
    f.native_fault.className = c.native_fault ? "bad" : "";
    set(f.fault_mask, hex(c.fault_mask, 8));
    set(f.data_age_ms, age(ageMs) + (stale && !d.comm_lost && ageMs < NEVER ? " (stale)" : ""));
    f.data_age_ms.dataset.value = ageMs;
    card.ageMs = ageMs;
    f.data_age_ms.className = stale ? "agewarn" : "";
    set(f.failsafe, d.failsafe_latched ? "LATCHED" : "clear");
    f.failsafe.className = d.failsafe_latched ? "alarmfield" : "";
    set(f.heartbeat, c.heartbeat === undefined ? "-" : c.heartbeat);
    for (const [key] of COUNTERS) {
      set(f[key], num(c[key]));
      f[key].className = key !== "frames_good" && c[key] ? "nz" : "";
    }
    const points = d.points || [];
    const names = points.map((p) => p.name).join("\n");
    set(f.points_summary, "drive points (" + points.length + ")");
    if (names !== card.pointNames) {
      card.pointNames = names;
      f.points.replaceChildren();
      for (const p of points) {
        const tr = el("tr", {"data-point": p.name});
        tr.append(el("td", {"class": "name"}, p.name), el("td"), el("td", {"class": "l"}, p.unit || ""));
        f.points.append(tr);
      }
    }
    points.forEach((p, i) => {
      const v = p.value === null ? "-" : (typeof p.value === "number" ? p.value : String(p.value));
      set(f.points.children[i].children[1], p.label ? p.label + " (" + v + ")" : v);
    });
  }

  function syncRows(map, tbody, items, key, make) {
    const seen = new Set();
    items.forEach((item, i) => {
      const k = key(item);
      seen.add(k);
      let row = map.get(k);
      if (!row) { row = make(item); map.set(k, row); }
      if (tbody.children[i] !== row.tr) tbody.insertBefore(row.tr, tbody.children[i] || null);
    });
    for (const [k, row] of map) if (!seen.has(k)) { row.tr.remove(); map.delete(k); }
  }
  function makeRow(attr, value, fields) {
    const tr = el("tr", {[attr]: value});
    const f = {};
    for (const name of fields) {
      const td = el("td", {"data-field": name});
      if (name === "name" || name === "address") td.className = "name";
      if (["port", "open", "tls", "access", "word_order", "allow"].includes(name)) td.classList.add("l");
      f[name] = td;
      tr.append(td);
    }
    return {tr: tr, f: f};
  }

  function render(s) {
    const devices = s.devices || [];
    const box = $("devices");
    if (!devices.length) {
      cards.clear();
      box.replaceChildren(el("p", {"class": "empty"}, "no drives configured"));
    } else {
      const seen = new Set();
      if (box.firstChild && box.firstChild.tagName === "P") box.replaceChildren();
      devices.forEach((d, i) => {
        seen.add(d.name);
        let card = cards.get(d.name);
        if (!card) { card = makeCard(d); cards.set(d.name, card); }
        renderDevice(card, d);
        if (box.children[i] !== card.el) box.insertBefore(card.el, box.children[i] || null);
      });
      for (const [name, card] of cards) if (!seen.has(name)) { card.el.remove(); cards.delete(name); }
    }
    const count = (p) => devices.filter(p).length;
    const tiles = {
      devices: [devices.length, ""],
      running: [count((d) => (d.status_bits || []).includes("running")), ""],
      faulted: [count((d) => !d.comm_lost && ((d.common || {}).fault_code || 0) !== 0), "alarm"],
      comm_lost: [count((d) => d.comm_lost), "comm"],
      failsafe: [count((d) => d.failsafe_latched), "alarm"],
      clients: [(s.modbus || {}).clients, ""],
    };
    for (const k in tiles) {
      const t = document.querySelector('[data-summary="' + k + '"]');
      set(t.firstElementChild, num(tiles[k][0]));
      t.className = "tile" + (tiles[k][1] && tiles[k][0] ? " " + tiles[k][1] : "");
    }

    // Frames per bus: the drives' own counters summed over the drives on it.
    const perBus = {};
    for (const d of devices) {
      const c = d.common || {}, b = perBus[d.bus] || (perBus[d.bus] = {good: 0, bad: 0});
      b.good += Number(c.frames_good) || 0;
      b.bad += Number(c.bad_checksum) || 0;
    }
    const busFields = ["name", "port", "open", "exchanges", "frames_good", "bad_frames",
      "timeouts", "retries", "echo_errors", "noise_bytes", "reopens", "bytes", "utilisation"];
    const buses = s.buses || [];
    syncRows(busRows, document.querySelector("#buses tbody"), buses, (b) => b.name,
      (b) => makeRow("data-bus", b.name, busFields));
    for (const b of buses) {
      const f = busRows.get(b.name).f, agg = perBus[b.name] || {good: 0, bad: 0};
      set(f.name, b.name);
      set(f.port, b.port + " @ " + b.baud);
      if (f.open.dataset.open !== String(b.open)) {
        f.open.dataset.open = String(b.open);
        f.open.replaceChildren(el("span", {"class": "pill " + (b.open ? "open" : "reopen")}, b.open ? "open" : "reopening"));
      }
      for (const k of ["exchanges", "timeouts", "retries", "echo_errors", "noise_bytes", "reopens"]) {
        set(f[k], num(b[k]));
        if (k !== "exchanges") f[k].className = b[k] ? "nz" : "";
      }
      set(f.bytes, num(b.bytes_sent) + " / " + num(b.bytes_received));
      set(f.frames_good, num(agg.good));
      set(f.bad_frames, num(agg.bad));
      f.bad_frames.className = agg.bad ? "nz" : "";
      const prev = prevBusy.get(b.name);
      const busy = Number(b.line_busy_seconds);
      let util = null;
      // Over at least half a second of daemon time: one frame more or less in a short window
      // would swing it from 0 to 100 %.
      if (prev && s.now - prev.now >= 0.5 && busy >= prev.busy) {
        util = Math.min(1, (busy - prev.busy) / (s.now - prev.now));
      } else if (!f.utilisation.dataset.value && s.now - s.started >= 0.5) {
        util = Math.min(1, busy / (s.now - s.started));  // until then: the mean since start-up
      }
      if (!prev || s.now - prev.now >= 0.5 || busy < prev.busy) prevBusy.set(b.name, {busy: busy, now: s.now});
      if (util !== null || !f.utilisation.firstChild) {
        const bar = el("span", {"class": "util"});
        const fill = el("i");
        fill.style.width = util === null ? "0" : (util * 100).toFixed(1) + "%";
        bar.append(fill);
        f.utilisation.replaceChildren(util === null ? "-" : (util * 100).toFixed(1) + " %", bar);
        f.utilisation.dataset.value = util === null ? "" : util.toFixed(4);
      }
    }
    if (!buses.length) document.querySelector("#buses tbody").replaceChildren();

    const lisFields = ["address", "tls", "access", "word_order", "allow", "clients", "max_clients",
      "accepted", "refused", "evicted", "not_allowed", "tls_handshake_failures",
      "tls_handshakes_limited", "writes_denied"];
    const listeners = s.listeners || [];
    syncRows(lisRows, document.querySelector("#listeners tbody"), listeners, (l) => l.address,
      (l) => makeRow("data-listener", l.address, lisFields));
    for (const l of listeners) {
      const f = lisRows.get(l.address).f;
      set(f.address, l.address);
      set(f.tls, l.tls ? "yes" : "no");
      set(f.access, l.access);
      set(f.word_order, l.word_order);
      set(f.allow, (l.allow || []).length ? l.allow.join(", ") : "any");
      for (const k of ["clients", "max_clients", "accepted", "refused", "evicted", "not_allowed",
        "tls_handshake_failures", "tls_handshakes_limited", "writes_denied"]) {
        set(f[k], num(l[k]));
        if (!["clients", "max_clients", "accepted", "evicted"].includes(k)) {
          f[k].className = l[k] ? "nz" : "";
        }
      }
    }
    const m = s.modbus || {};
    for (const k of ["clients", "requests", "malformed", "refused"]) {
      set(document.querySelector('#modbus [data-field="' + k + '"]'), num(m[k]));
    }
    const q = s.mqtt, mq = $("mqtt");
    mq.hidden = !q;
    if (q) {
      const field = (k) => mq.querySelector('[data-field="' + k + '"]');
      set(field("broker"), q.broker);
      set(field("session"), q.session);
      field("session").className = q.session === "online" ? "" : "nz";
      for (const k of ["bd_seq", "connects", "losses", "messages", "births", "commands"]) {
        set(field(k), num(q[k]));
      }
      set(field("last_error"), q.last_error ? "\u00b7 last error: " + q.last_error : "");
    }
    set($("version"), s.version ? "v" + s.version : "");
    const restart = $("restart"), needed = s.restart_needed || [];
    restart.hidden = needed.length === 0;
    set(restart, needed.length === 0 ? "" : "Restart needed: the configuration file changes " +
        needed.join(", ") + ", which only a restart applies (systemctl restart drivegate)");
    set($("now"), clock(s.now));
    set($("uptime"), duration(s.now - s.started));
  }

  function showLink() {
    const body = document.body, banner = $("banner");
    if (failingSince === null) {
      body.dataset.link = "live";
      set($("link-text"), "live");
      banner.hidden = true;
    } else {
      body.dataset.link = "unreachable";
      set($("link-text"), "daemon unreachable");
      const since = (Date.now() - failingSince.at) / 1000;
      banner.hidden = false;
      // The values age while nobody answers: every drive's data is at least that much older.
      for (const card of cards.values()) {
        if (lastGood && card.ageMs !== undefined && card.ageMs < NEVER) {
          set(card.f.data_age_ms, "> " + age(card.ageMs + Date.now() - lastGood.local) + " (not live)");
          card.f.data_age_ms.className = "agewarn";
        }
      }
      set(banner, "The daemon does not answer (" + failingSince.reason + ", for " + since.toFixed(0) +
        " s). " + (lastGood ? "Values below are the last received, at " + clock(lastGood.now) +
        " daemon time; they are not live." : "No data received yet."));
    }
    set($("age"), lastGood ? age(Date.now() - lastGood.local) + " ago" : "-");
  }

  async function poll() {
    const started = performance.now();
    const abort = new AbortController();
    const timer = setTimeout(() => abort.abort(), TIMEOUT_MS);
    try {
      const r = await fetch("/api/v1/status", {cache: "no-store", signal: abort.signal});
      if (!r.ok) throw new Error("HTTP " + r.status);
      const s = await r.json();
      render(s);
      lastGood = {now: s.now, local: Date.now()};
      failingSince = null;
      document.body.dataset.updates = String(++updates);
    } catch (e) {
      if (failingSince === null) failingSince = {at: Date.now(), reason: ""};
      failingSince.reason = e && e.name === "AbortError" ? "no answer in " + TIMEOUT_MS / 1000 + " s"
        : (e && e.message ? e.message : "request failed");
    } finally {
      clearTimeout(timer);
      showLink();
      setTimeout(poll, Math.max(0, REFRESH_MS - (performance.now() - started)));
    }
  }
  poll();
})();
