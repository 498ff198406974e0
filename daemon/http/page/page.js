"use strict";
(function () {
  const REFRESH_MS = Number(document.body.dataset.refreshMs) || 1000;
  const TIMEOUT_MS = 2500;      // a request that hangs longer counts as unreachable
  const STALE_MS = 3000;        // drive data older than this is greyed out
  const NEVER = 4294967295;     // data_age_ms of a drive never heard from
  // Trends (/api/v1/trends): the daemon samples once a second and keeps 10 minutes.
  const TREND_KEEP_MS = 600000;
  const SPARK_MIN_SPAN_MS = 60000;  // a young trend is drawn over a minute, not stretched thin
  const GAP_MS = 3500;          // rows further apart than this: the daemon was away; lift the pen
  // Events (/api/v1/events): rows kept on the page, newest first.
  const MAX_EVENT_ROWS = 200;
  const REPEAT_LOOKBACK = 64;   // newest entries asked for again now and then (repeat counts)
  const REPEATS_EVERY = 5;      // polls between two looks back for repeat counts
  const ALARM_KINDS = ["fault_raised", "comm_lost", "failsafe_tripped"];
  const CLEAR_KINDS = ["fault_cleared", "comm_restored", "failsafe_cleared"];
  const COUNTERS = [["frames_good", "frames good"], ["bad_checksum", "bad checksum"],
    ["timeouts", "timeouts"], ["retries", "retries"], ["nacks", "nacks"],
    ["foreign_frames", "foreign"]];
  const $ = (id) => document.getElementById(id);
  const cards = new Map();      // device name -> {el, f: {field: element}, pointNames}
  const busRows = new Map();
  const lisRows = new Map();
  const serRows = new Map();
  const prevBusy = new Map();   // bus name -> {busy, now}: line utilisation between two polls
  let lastGood = null;          // daemon's `now` and local time of the last good answer
  let failingSince = null;     // {at: local ms, reason} while the daemon does not answer
  let updates = 0;
  // Trends by key ("device:NAME", "bus:NAME"), oldest row first:
  // {series: [{name, unit}], sig, t: [unix ms], values: [[per series, null: unknown]]}.
  const trends = new Map();
  // The events panel: the newest sequence number shown and its rows by sequence number.
  const events = {lastSeq: 0, rows: new Map(), polls: 0};
  let chart = null;             // the open chart: {key, byLink}; null when closed

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
    const spark = makeSpark("device:" + d.name, "speed (setpoint dashed)");
    values.append(speed, bar, spark.box, kv, counters);
    const det = el("details");
    f.points_summary = el("summary", null, "drive points");
    f.points = field("tbody", "points");
    const pt = el("table");
    pt.append(f.points);
    det.append(f.points_summary, pt);
    card.append(head, sub, comm, badges, values, det);
    return {el: card, f: f, pointNames: "", spark: spark};
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
      if (["port", "open", "tls", "access", "word_order", "allow", "trend", "framing"].includes(name)) td.classList.add("l");
      if (["name", "port", "allow"].includes(name)) td.classList.add("clip");
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
      "timeouts", "retries", "echo_errors", "noise_bytes", "reopens", "bytes", "utilisation", "trend"];
    const buses = s.buses || [];
    syncRows(busRows, document.querySelector("#buses tbody"), buses, (b) => b.name,
      (b) => makeRow("data-bus", b.name, busFields));
    for (const b of buses) {
      const row = busRows.get(b.name), f = row.f, agg = perBus[b.name] || {good: 0, bad: 0};
      if (!row.spark) {
        row.spark = makeSpark("bus:" + b.name, "utilisation");
        f.trend.append(row.spark.box);
      }
      set(f.name, b.name);
      f.name.title = b.name;
      set(f.port, b.port + " @ " + b.baud);
      f.port.title = f.port.textContent;  // ellipsized when long: the whole path on hover
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
      f.allow.title = f.allow.textContent;
      for (const k of ["clients", "max_clients", "accepted", "refused", "evicted", "not_allowed",
        "tls_handshake_failures", "tls_handshakes_limited", "writes_denied"]) {
        set(f[k], num(l[k]));
        if (!["clients", "max_clients", "accepted", "evicted"].includes(k)) {
          f[k].className = l[k] ? "nz" : "";
        }
      }
    }
    // The RTU / ASCII listeners (docs/serial-listeners.md): each <tr data-serial="PORT">.
    const serial = s.serial_listeners || [];
    $("serial").hidden = !serial.length;
    const serCounts = ["frames", "requests", "crc_errors", "exceptions", "not_answered",
      "broken_frames", "other_units", "broadcasts", "broadcasts_refused"];
    syncRows(serRows, document.querySelector("#serial-listeners tbody"), serial, (l) => l.port,
      (l) => makeRow("data-serial", l.port, ["port", "framing", "access", "open"].concat(serCounts)));
    for (const l of serial) {
      const f = serRows.get(l.port).f;
      set(f.port, l.port);
      set(f.framing, l.framing);
      set(f.access, l.access);
      set(f.open, l.open ? "yes" : "no");
      f.open.classList.toggle("nz", !l.open);
      for (const k of serCounts) {
        set(f[k], num(l[k]));
        if (["crc_errors", "not_answered", "broken_frames", "broadcasts_refused"].includes(k)) {
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
      set(field("broker"), q.brokers > 1
        ? q.broker + " (" + (q.broker_index + 1) + " of " + q.brokers + ")" : q.broker);
      set(field("session"), q.session);
      field("session").className = q.session === "online" ? "" : "nz";
      for (const k of ["bd_seq", "connects", "sessions_lost", "messages", "births", "commands"]) {
        set(field(k), num(q[k]));
      }
      // `losses` counts both: the sessions that were up and ended, and the attempts that failed.
      set(field("attempts_failed"), num(q.losses - q.sessions_lost));
      set(field("last_error"), q.last_error ? "\u00b7 last error: " + q.last_error : "");
      const st = q.store || {};
      set(field("store"), !st.enabled ? "" : "\u00b7 kept for later " + num(st.records) +
        " (" + num(Math.round(st.bytes / 1024)) + " KiB), sent " + num(st.replayed) +
        ", dropped " + num(st.dropped_size + st.dropped_age + st.dropped_lost +
        st.replay_dropped));
    }
    set($("version"), s.version ? "v" + s.version : "");
    const restart = $("restart"), needed = s.restart_needed || [];
    restart.hidden = needed.length === 0;
    set(restart, needed.length === 0 ? "" : "Restart needed: the configuration file changes " +
        needed.join(", ") + ", which only a restart applies (systemctl restart drivegate)");
    set($("now"), clock(s.now));
    set($("uptime"), duration(s.now - s.started));
  }

  // ---- Trends: /api/v1/trends, merged into `trends` a few rows at a time ------------------

  // Rows at or after this daemon time (Unix seconds) are the ones not held yet for some trend:
  // after the oldest "newest row" among them, so a trend sampled a little apart from the others
  // loses nothing (rows already held are skipped by mergeTrends), but never more than a few
  // samples back, so that one trend that stopped growing does not have every answer carry all
  // ten minutes again. null: ask for everything.
  function trendsSince() {
    let oldest = Infinity, newest = -Infinity;
    for (const tr of trends.values()) {
      if (!tr.t.length) continue;
      oldest = Math.min(oldest, tr.t[tr.t.length - 1]);
      newest = Math.max(newest, tr.t[tr.t.length - 1]);
    }
    if (oldest === Infinity) return null;
    return ((Math.max(oldest, newest - 10000) + 1) / 1000).toFixed(3);
  }

  function mergeTrends(doc) {
    const seen = new Set();
    for (const tr of doc.trends || []) {
      if (typeof tr.name !== "string" || !Array.isArray(tr.t) || !Array.isArray(tr.series)) continue;
      seen.add(tr.name);
      const sig = tr.series.map((x) => x.name + "\u0000" + x.unit).join("\u0001");
      let mine = trends.get(tr.name);
      if (!mine || mine.sig !== sig) {
        // New, or its series changed (a reload changed the drive): the daemon started it anew.
        mine = {series: tr.series, sig: sig, t: [], values: tr.series.map(() => [])};
        trends.set(tr.name, mine);
      }
      const values = Array.isArray(tr.values) ? tr.values : [];
      tr.t.forEach((t, i) => {
        if (typeof t !== "number" || (mine.t.length && t <= mine.t[mine.t.length - 1])) return;
        mine.t.push(t);
        mine.values.forEach((col, k) => {
          const v = (values[k] || [])[i];
          col.push(typeof v === "number" && isFinite(v) ? v : null);
        });
      });
      // What the daemon no longer keeps, neither does the page.
      const from = mine.t.length ? mine.t[mine.t.length - 1] - TREND_KEEP_MS : 0;
      let drop = 0;
      while (drop < mine.t.length && mine.t[drop] < from) drop++;
      if (drop) {
        mine.t.splice(0, drop);
        for (const col of mine.values) col.splice(0, drop);
      }
    }
    // A drive or bus a reload removed is gone from every answer.
    for (const k of [...trends.keys()]) if (!seen.has(k)) trends.delete(k);
  }

  function column(trend, name) {
    const i = trend ? trend.series.findIndex((x) => x.name === name) : -1;
    return i < 0 ? null : {values: trend.values[i], unit: trend.series[i].unit};
  }

  // ---- SVG line drawing, shared by the sparklines and the chart ----------------------------

  const SVG_NS = "http://www.w3.org/2000/svg";
  function svg(tag, attrs) {
    const e = document.createElementNS(SVG_NS, tag);
    for (const k in attrs || {}) e.setAttribute(k, attrs[k]);
    return e;
  }
  // The time window to draw: the trend's own span up to its newest row, at least `minSpan`.
  function timeSpan(t, minSpan) {
    const t1 = t.length ? t[t.length - 1] : 0;
    return {t0: t1 - Math.max(minSpan, t.length ? t1 - t[0] : 0), t1: t1};
  }
  // Lowest and highest known value of the columns over the rows from `t0` on; null if none.
  function extent(t, cols, t0) {
    let lo = Infinity, hi = -Infinity;
    for (const col of cols) {
      col.forEach((v, i) => {
        if (v === null || t[i] < t0) return;
        lo = Math.min(lo, v);
        hi = Math.max(hi, v);
      });
    }
    return lo === Infinity ? null : {lo: lo, hi: hi};
  }
  // An SVG path of `v` over times `t`, in a w x h box mapping [t0, t1] x [lo, hi]. The pen
  // lifts over unknown values (null: the drive's link was lost) and over gaps in the sampling,
  // so nothing is drawn that was not measured.
  function linePath(t, v, box) {
    const sx = box.w / Math.max(1, box.t1 - box.t0), sy = box.h / (box.hi - box.lo || 1);
    let d = "", pen = false;
    for (let i = 0; i < t.length; i++) {
      if (i > 0 && t[i] - t[i - 1] > GAP_MS) pen = false;
      if (v[i] === null || t[i] < box.t0) { pen = false; continue; }
      const x = ((t[i] - box.t0) * sx).toFixed(1), y = (box.h - (v[i] - box.lo) * sy).toFixed(1);
      // A lone sample still shows, as a short dash.
      d += pen ? "L" + x + " " + y : "M" + x + " " + y + "h0.5";
      pen = true;
    }
    return d;
  }
  function spanText(ms) {
    return ms >= 60000 ? Math.round(ms / 60000) + " min" : Math.round(ms / 1000) + " s";
  }
  function fmt(v) {
    if (v === null || v === undefined) return "-";
    const a = Math.abs(v);
    return v.toLocaleString("en-US", {maximumFractionDigits: a >= 100 ? 0 : a >= 10 ? 1 : 2});
  }

  // ---- Sparklines: one per drive (speed, setpoint dashed) and one per bus (utilisation) ----

  const SPARK_W = 300, SPARK_H = 34;
  // A link that opens the chart of trend `key`, holding an SVG stretched to its box
  // (preserveAspectRatio none; vector-effect keeps the strokes thin), and a caption.
  function makeSpark(key, what) {
    const box = el("a", {"class": "spark", "href": "#chart=" + encodeURIComponent(key)});
    const s = svg("svg", {"viewBox": "0 0 " + SPARK_W + " " + SPARK_H, "preserveAspectRatio": "none",
      "data-spark": key, "data-last": "", "data-samples": "0", "aria-hidden": "true"});
    const zero = svg("path", {"class": "zero"});
    const dashed = svg("path", {"class": "sp"});
    const line = svg("path", {"class": "pv"});
    s.append(zero, dashed, line);
    const cap = el("span", {"class": "cap"});
    const span = el("span", null, "no trend yet");
    cap.append(span, el("span", {"class": "more"}, "chart \u203a"));
    box.append(s, cap);
    return {key: key, what: what, box: box, svg: s, zero: zero, dashed: dashed, line: line, span: span};
  }

  // Draws series `name` (and `dashedName` dashed, on the same scale) of the spark's trend.
  function drawSpark(sp, name, dashedName, floorHi) {
    const trend = trends.get(sp.key);
    const pv = column(trend, name), sv = dashedName ? column(trend, dashedName) : null;
    const t = trend ? trend.t : [];
    if (!pv || !t.length) {
      for (const p of [sp.zero, sp.dashed, sp.line]) p.setAttribute("d", "");
      sp.svg.dataset.last = "";
      sp.svg.dataset.samples = "0";
      set(sp.span, trend ? "no " + name + " trend" : "no trend yet");
      sp.box.title = sp.what + ": no trend yet";
      return;
    }
    const w = timeSpan(t, SPARK_MIN_SPAN_MS);
    const cols = sv ? [pv.values, sv.values] : [pv.values];
    const ext = extent(t, cols, w.t0) || {lo: 0, hi: 0};
    // Speeds and utilisations are drawn from 0 (or below, reversing): a flat line at the top
    // would hide how fast the drive goes.
    const lo = Math.min(0, ext.lo), hi = Math.max(ext.hi, floorHi || 0, lo + 1);
    const box = {t0: w.t0, t1: w.t1, lo: lo - (hi - lo) * 0.06, hi: hi + (hi - lo) * 0.1,
      w: SPARK_W, h: SPARK_H};
    sp.line.setAttribute("d", linePath(t, pv.values, box));
    sp.dashed.setAttribute("d", sv ? linePath(t, sv.values, box) : "");
    const y0 = (SPARK_H - (0 - box.lo) * SPARK_H / (box.hi - box.lo)).toFixed(1);
    sp.zero.setAttribute("d", "M0 " + y0 + "H" + SPARK_W);
    // For tests and scrapers: what the line ends on (the newest row; "" when unknown).
    const last = pv.values[pv.values.length - 1];
    sp.svg.dataset.last = last === null ? "" : String(last);
    sp.svg.dataset.lastT = String(t[t.length - 1]);
    sp.svg.dataset.samples = String(t.length);
    if (sv) {
      const lastSp = sv.values[sv.values.length - 1];
      sp.svg.dataset.setpoint = lastSp === null ? "" : String(lastSp);
    }
    const unit = pv.unit ? " " + pv.unit : "";
    const own = extent(t, [pv.values], w.t0);  // the peak of the line itself, not the setpoint's
    set(sp.span, "last " + spanText(w.t1 - w.t0) + (own ? " \u00b7 peak " + fmt(own.hi) + unit : ""));
    sp.box.title = sp.what + " over the last " + spanText(w.t1 - w.t0) + " (now " + fmt(last) + unit +
      "); click for the chart";
  }

  function drawTrends() {
    for (const card of cards.values()) drawSpark(card.spark, "speed_rpm", "setpoint_rpm");
    for (const row of busRows.values()) if (row.spark) drawSpark(row.spark, "utilisation", null, 5);
    if (chart) renderChart();
  }

  // ---- The chart: every series of one trend, on demand (#chart=KEY), one panel each -------

  const CHART_W = 800, CHART_H = 64;
  function chartKeyOf(hash) {
    const m = /^#chart=(.+)$/.exec(hash || "");
    if (!m) return null;
    try { return decodeURIComponent(m[1]); } catch (e) { return null; }
  }
  function openChart(key, byLink) {
    // Focus goes back to what opened it (the sparkline's link) when it closes.
    chart = {key: key, byLink: byLink, opener: document.activeElement};
    $("chart").hidden = false;
    renderChart();
    $("chart-close").focus();
  }
  function hideChart() {
    const opener = chart.opener;
    chart = null;
    $("chart").hidden = true;
    if (opener && opener.focus && document.contains(opener)) opener.focus();
  }
  function closeChart() {
    if (!chart) return;
    const byLink = chart.byLink;
    hideChart();
    // Opened by a link on this page: going back closes it (and the back button does the same).
    // Opened from an address with #chart=: dropping the fragment keeps the visitor on the page.
    if (byLink && chartKeyOf(location.hash) !== null) history.back();
    else if (location.hash) history.replaceState(null, "", location.pathname + location.search);
  }
  // The chart follows the address: #chart=KEY opens it (a sparkline's link, the back and forward
  // buttons, an address typed or shared), anything else closes it.
  function followHash(byLink) {
    const key = chartKeyOf(location.hash);
    if (key !== null) openChart(key, byLink);
    else if (chart) hideChart();
  }

  // Panels: the speed with its setpoint dashed on the same scale, then every other series.
  function chartPanels(trend) {
    const names = trend.series.map((x) => x.name);
    const panels = [];
    for (const name of names) {
      if (name === "setpoint_rpm" && names.includes("speed_rpm")) continue;
      panels.push({name: name, dashed: name === "speed_rpm" && names.includes("setpoint_rpm") ? "setpoint_rpm" : null});
    }
    return panels;
  }

  function renderChart() {
    const key = chart.key, trend = trends.get(key);
    const colon = key.indexOf(":");
    const kind = key.slice(0, colon), name = key.slice(colon + 1);
    set($("chart-title"), (kind === "bus" ? "Bus " : "") + name);
    $("chart").dataset.chart = key;
    const body = $("chart-body");
    if (!trend || !trend.t.length) {
      set($("chart-meta"), "");
      body.replaceChildren(el("p", {"class": "empty"}, trends.size ? "no trend of that name" : "waiting for the trends\u2026"));
      return;
    }
    const t = trend.t, w = timeSpan(t, SPARK_MIN_SPAN_MS);
    set($("chart-meta"), t.length + " samples, one a second \u00b7 last " + spanText(w.t1 - w.t0) +
      " \u00b7 gaps: unknown (link lost)");
    const out = [];
    for (const p of chartPanels(trend)) {
      const pv = column(trend, p.name), sv = p.dashed ? column(trend, p.dashed) : null;
      const cols = sv ? [pv.values, sv.values] : [pv.values];
      const ext = extent(t, cols, w.t0);
      const unit = pv.unit || "";
      const panel = el("div", {"class": "panel", "data-series": p.name});
      const info = el("div", {"class": "info"});
      const last = pv.values[pv.values.length - 1];
      info.append(el("b", null, p.name + (sv ? " \u00b7 " + p.dashed + " (dashed)" : "")),
        el("span", {"class": "now"}, fmt(last) + (unit ? " " + unit : "")),
        el("span", {"class": "mm"}, ext ? "min " + fmt(ext.lo) + " \u00b7 max " + fmt(ext.hi) : "no values"));
      // Its own scale: the series' range, padded; a flat line sits mid-height.
      let lo = ext ? ext.lo : 0, hi = ext ? ext.hi : 1;
      if (hi - lo < 1e-9) { lo -= 1; hi += 1; }
      const pad = (hi - lo) * 0.08;
      const box = {t0: w.t0, t1: w.t1, lo: lo - pad, hi: hi + pad, w: CHART_W, h: CHART_H};
      const axis = el("div", {"class": "yaxis"});
      axis.append(el("span", null, fmt(hi)), el("span", {"class": "u"}, unit), el("span", null, fmt(lo)));
      const s = svg("svg", {"viewBox": "0 0 " + CHART_W + " " + CHART_H, "preserveAspectRatio": "none"});
      // A faint line each whole minute: the time axis below labels them.
      let grid = "";
      for (let m = Math.ceil(w.t0 / 60000) * 60000; m <= w.t1; m += 60000) {
        grid += "M" + ((m - w.t0) * CHART_W / (w.t1 - w.t0)).toFixed(1) + " 0V" + CHART_H;
      }
      s.append(svg("path", {"class": "grid", "d": grid}));
      if (sv) s.append(svg("path", {"class": "sp", "d": linePath(t, sv.values, box)}));
      s.append(svg("path", {"class": "pv", "d": linePath(t, pv.values, box)}));
      panel.append(info, axis, s);
      out.push(panel);
    }
    const taxis = el("div", {"class": "panel taxis"});
    const ticks = el("div", {"class": "ticks"});
    ticks.append(el("span", null, clock(w.t0 / 1000)), el("span", null, clock((w.t0 + w.t1) / 2000)),
      el("span", null, clock(w.t1 / 1000)));
    taxis.append(el("div"), el("div"), ticks);
    out.push(taxis);
    body.replaceChildren(...out);
  }

  // ---- Events: /api/v1/events, newest first, MAX_EVENT_ROWS at most ----------------------

  function eventsUrl() {
    if (!events.lastSeq) return "/api/v1/events?limit=" + MAX_EVENT_ROWS;
    // New entries only, after the newest shown. Every few polls the request also goes back over
    // the newest few: a command repeated (a PLC writing every scan) updates its entry in place,
    // "repeats" and "last_ms", without a new sequence number.
    const back = events.polls % REPEATS_EVERY === 0 ? REPEAT_LOOKBACK : 0;
    return "/api/v1/events?after=" + Math.max(0, events.lastSeq - back) + "&limit=" + MAX_EVENT_ROWS;
  }

  function eventTime(ms) {
    const d = new Date(ms);
    return clock(ms / 1000) + "." + String(d.getMilliseconds()).padStart(3, "0");
  }

  function repeatText(f) {
    const n = Number(f.repeats);
    if (!n) return "";
    return "\u00d7" + (n + 1) + (f.last_ms ? ", last " + eventTime(Number(f.last_ms)) : "");
  }

  // What a command did, in parts: who (source, client, listener, certificate, role), what
  // (the points written), and what came of it; a refusal stands out.
  function commandWhat(e, f) {
    const what = el("td", {"class": "what"});
    const who = el("span", {"class": "who"});
    who.append(el("span", {"class": "src"}, f.source || "?"));
    if (f.client) who.append(" ", el("span", {"class": "client"}, f.client));
    if (f.listener) who.append(el("span", {"class": "dim"}, " on " + f.listener));
    if (f.subject) who.append(el("span", {"class": "dim"}, ", certificate " + f.subject));
    if (f.role) who.append(el("span", {"class": "dim"}, ", role " + f.role));
    const ok = f.result === "ok";
    const res = el("span", {"class": "res " + (ok ? "ok" : "refused")}, (f.result || "?").replace(/_/g, " "));
    what.append(who, " ", el("span", {"class": "pts"}, f.points || "(nothing)"), " \u2192 ", res);
    if (f.why) what.append(el("span", {"class": "why"}, " " + f.why));
    if (f.took_ms) what.append(el("span", {"class": "dim"}, " " + f.took_ms + " ms"));
    // A summary of a flood's writes (docs/audit.md): how many, over what time, the last shown.
    if (f.folded) {
      what.append(el("span", {"class": "dim"}, " (" + f.folded + " writes folded into this record" +
        (f.since_ms ? ", " + eventTime(Number(f.since_ms)) + " to " + eventTime(Number(f.last_ms)) : "") +
        (f.spread ? ", every " + (f.spread === "source" ? "client of the kind" : "device and point") : "") +
        ")"));
    }
    what.append(el("span", {"class": "rep"}, repeatText(f)));
    return what;
  }

  function eventRow(e) {
    const f = e.fields && typeof e.fields === "object" ? e.fields : {};
    const kind = String(e.kind || "");
    const cls = ALARM_KINDS.includes(kind) ? "alarm" : CLEAR_KINDS.includes(kind) ? "clear"
      : kind === "command" && f.result !== "ok" ? "refused" : "";
    // data-drive, not data-device: that one names the drives' cards.
    const tr = el("tr", {"data-seq": String(e.seq), "data-kind": kind, "data-drive": String(e.device || "")});
    if (cls) tr.className = cls;
    if (kind === "command") {
      tr.dataset.source = f.source || "";
      tr.dataset.client = f.client || "";
      tr.dataset.result = f.result || "";
    }
    const when = el("td", {"class": "time", "title": new Date(e.unix_ms).toString()}, eventTime(e.unix_ms));
    const kindTd = el("td");
    kindTd.append(el("span", {"class": "kind"}, kind.replace(/_/g, " ")));
    const dev = el("td", {"class": "dev"}, e.device || "gateway");
    if (e.unit) dev.append(el("small", null, " unit " + e.unit));
    dev.title = dev.textContent;
    let what;
    if (kind === "command") {
      what = commandWhat(e, f);
    } else {
      what = el("td", {"class": "what"}, String(e.message || ""));
      what.append(el("span", {"class": "rep"}, repeatText(f)));
    }
    tr.append(when, kindTd, dev, what);
    return tr;
  }

  function mergeEvents(doc) {
    if (typeof doc.last_seq !== "number") return;
    const tbody = document.querySelector("#events tbody");
    if (doc.last_seq < events.lastSeq) {
      // The daemon restarted: its numbering starts again; the next poll asks for everything.
      tbody.replaceChildren();
      events.rows.clear();
      events.lastSeq = 0;
      return;
    }
    for (const e of doc.events || []) {
      if (typeof e.seq !== "number") continue;
      const shown = events.rows.get(e.seq);
      if (shown) {  // asked again for its repeat count
        const rep = shown.querySelector(".rep");
        if (rep) set(rep, repeatText(e.fields || {}));
        continue;
      }
      if (e.seq <= events.lastSeq) continue;  // older than the rows kept: let it go
      const tr = eventRow(e);
      events.rows.set(e.seq, tr);
      tbody.insertBefore(tr, tbody.firstChild);  // they come oldest first: newest ends on top
      events.lastSeq = e.seq;
    }
    while (tbody.children.length > MAX_EVENT_ROWS) {
      const tr = tbody.lastElementChild;
      events.rows.delete(Number(tr.dataset.seq));
      tr.remove();
    }
    $("events-empty").hidden = tbody.children.length > 0;
    set($("events-meta"), "newest first \u00b7 " + tbody.children.length + " shown of the daemon's " +
      num(doc.capacity) + " kept" + (doc.dropped ? " \u00b7 " + num(doc.dropped) + " older dropped" : ""));
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

  // GET `url` as JSON, given up on after TIMEOUT_MS.
  async function getJson(url) {
    const abort = new AbortController();
    const timer = setTimeout(() => abort.abort(), TIMEOUT_MS);
    try {
      const r = await fetch(url, {cache: "no-store", signal: abort.signal});
      if (!r.ok) throw new Error("HTTP " + r.status);
      return await r.json();
    } catch (e) {
      throw e && e.name === "AbortError" ? new Error("no answer in " + TIMEOUT_MS / 1000 + " s") : e;
    } finally {
      clearTimeout(timer);
    }
  }

  // One round: the status, the trends since the newest row held and the events after the
  // newest shown, asked at once and rendered in that order (the cards the sparklines go in
  // first). Only the status decides whether the daemon is reachable: a daemon without the
  // history routes still gets its live page.
  async function poll() {
    const started = performance.now();
    const since = trendsSince();
    const asks = [getJson("/api/v1/status"),
      getJson("/api/v1/trends" + (since === null ? "" : "?since=" + since)),
      getJson(eventsUrl())];
    for (const a of asks) a.catch(() => {});  // each is awaited below; none left unhandled
    try {
      await round(asks);
    } finally {
      setTimeout(poll, Math.max(0, REFRESH_MS - (performance.now() - started)));
    }
  }
  async function round(asks) {
    try {
      const s = await asks[0];
      render(s);
      lastGood = {now: s.now, local: Date.now()};
      failingSince = null;
      document.body.dataset.updates = String(++updates);
    } catch (e) {
      if (failingSince === null) failingSince = {at: Date.now(), reason: ""};
      failingSince.reason = e && e.message ? e.message : "request failed";
    }
    showLink();
    try {
      mergeTrends(await asks[1]);
    } catch (e) {
      // Kept as they were: the sparklines show the last trends received.
    }
    drawTrends();
    try {
      mergeEvents(await asks[2]);
      events.polls++;
    } catch (e) {
      if (failingSince === null) set($("events-meta"), "not available (" + (e && e.message ? e.message : "request failed") + ")");
    }
  }

  window.addEventListener("hashchange", () => followHash(true));
  $("chart-close").addEventListener("click", (e) => { e.preventDefault(); closeChart(); });
  $("chart").addEventListener("click", (e) => { if (e.target === $("chart")) closeChart(); });
  document.addEventListener("keydown", (e) => { if (e.key === "Escape" && chart) closeChart(); });
  followHash(false);
  poll();
})();
