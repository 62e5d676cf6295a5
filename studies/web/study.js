/*
 * prg-study: the questionnaire page of a human-vs-robot handwriting study (no dependencies but
 * common.js, loaded before it).
 *
 * Reads window.PRG_STUDY_CONFIG (config.js) and window.PRG_STUDY_TRIALS (trials.js), both written
 * by `prg-study build`, so the page runs from file:// and from any static host.
 *
 * Flow: consent -> instructions (stimuli preloaded) -> trials -> save -> completion.
 *   study "turing":      pick the robot's sample among n, then confidence 1-5;
 *   study "readability": type the word shown.
 * URL parameters: PROLIFIC_PID, STUDY_ID, SESSION_ID (recorded); row=N picks trial list
 * row N (1-based); without it the row is fnv1a32(name + ":" + PROLIFIC_PID) mod rows, or random
 * when there is no PROLIFIC_PID.
 * Responses: one CSV row per trial with exactly config.columns; downloaded and/or POSTed
 * (as text/plain: no CORS preflight) to config.save.post_url; then the completion code is shown and the page
 * redirects to config.completion.redirect_url.
 * A pilot build (config.pilot) has its PILOT banner in index.html above every screen, names its
 * download PILOT_...; a not-ready build links its pilot copy (config.pilot_copy) when it has one.
 * Trial screens set body.trial-turing / body.trial-readability: study.css fits them to a large
 * window (no scrolling at 1280x800) and lets a phone scroll down, never sideways.
 */
(function () {
  "use strict";

  var cfg = window.PRG_STUDY_CONFIG;
  var list = window.PRG_STUDY_TRIALS;
  var app = document.getElementById("app");
  var page = window.PRGPage;  // common.js
  var el = page.el;

  // ------------------------------------------------------------------ small helpers
  // `screen` names the screen's layout (study.css): "trial-turing" and "trial-readability" fit
  // the window on a large screen; the others flow.
  function show(nodes, screen) {
    document.body.className = screen || "";
    page.show(app, nodes);
    window.scrollTo(0, 0);
  }

  function fnv1a32(text) {
    var bytes = new TextEncoder().encode(text);
    var h = 0x811c9dc5;
    for (var i = 0; i < bytes.length; i++) {
      h ^= bytes[i];
      h = Math.imul(h, 0x01000193) >>> 0;
    }
    return h >>> 0;
  }

  function randomHex(n) {
    var bytes = new Uint8Array(n);
    (window.crypto || window.msCrypto).getRandomValues(bytes);
    return Array.prototype.map.call(bytes, function (b) {
      return ("0" + b.toString(16)).slice(-2);
    }).join("");
  }

  function normalise(text) {  // the analysis' rule: trimmed, case-folded, spaces collapsed
    return String(text).trim().split(/\s+/).join(" ").toLowerCase();
  }

  function csvCell(value) {
    if (value === null || value === undefined) return "";
    var s = typeof value === "boolean" ? (value ? "true" : "false") : String(value);
    return /[",\r\n]/.test(s) ? '"' + s.replace(/"/g, '""') + '"' : s;
  }

  function toCSV(columns, records) {
    var lines = [columns.join(",")];
    records.forEach(function (r) {
      lines.push(columns.map(function (c) { return csvCell(r[c]); }).join(","));
    });
    return lines.join("\r\n") + "\r\n";
  }

  // ------------------------------------------------------------------ participant and row
  var params = new URLSearchParams(window.location.search);
  var rows = (list && list.rows) || [];

  function pickRow() {
    var n = rows.length;
    var asked = params.get("row");
    if (asked !== null && /^\d+$/.test(asked.trim())) {
      var k = parseInt(asked, 10);
      if (k >= 1 && k <= n) return { index: k - 1, how: "url" };
    }
    var pid = params.get("PROLIFIC_PID");
    if (pid) return { index: fnv1a32(cfg.name + ":" + pid) % n, how: "pid" };
    var r = new Uint32Array(1);
    window.crypto.getRandomValues(r);
    return { index: r[0] % n, how: "random" };
  }

  var state = {
    participant_id: params.get("PROLIFIC_PID") || "anon-" + randomHex(6),
    study_id: params.get("STUDY_ID") || "",
    session_id: params.get("SESSION_ID") || "",
    row: null,
    assignment: null,
    index: 0,
    records: [],
    finished: false,
    saved: null,
  };

  window.PRGStudy = {  // for researchers' debugging and the tests
    state: state,
    config: cfg,
    csv: function () { return toCSV(cfg.columns, state.records); },
    fnv1a32: fnv1a32,
  };

  function leaveWarning(event) {
    event.preventDefault();
    event.returnValue = "";
  }

  // ------------------------------------------------------------------ screens
  function notReady() {
    var items = (cfg.missing || []).map(function (m) { return el("li", { text: m }); });
    var pilot = [
      "To try the pages before then, use a PILOT copy (stand-in human samples made from the " +
      "robot's; never for data), built with prg-study build --pilot",
    ];
    if (cfg.pilot_copy) {
      pilot[0] += " beside this folder: ";
      pilot.push(el("a", { href: cfg.pilot_copy, id: "pilot-copy", text: cfg.pilot_copy }));
      pilot.push(" (the demo builds it).");
    } else {
      pilot[0] += ".";
    }
    show([
      el("h1", { text: cfg.title }),
      el("p", { class: "error", id: "not-ready", text: "This study is not ready to run yet." }),
      el("ul", {}, items),
      el("p", { class: "note", id: "pilot-hint" }, pilot),
    ]);
  }

  function consent() {
    var box = el("input", { type: "checkbox", id: "consent-agree" });
    var go = el("button", { class: "primary", id: "consent-continue", disabled: true, text: "Continue" });
    box.addEventListener("change", function () { go.disabled = !box.checked; });
    go.addEventListener("click", instructions);
    var no = el("button", { id: "consent-decline", text: "I do not agree" });
    no.addEventListener("click", function () {
      show([
        el("h1", { text: cfg.title }),
        el("p", { id: "declined", text: "You did not agree to take part; no answers were recorded. You may close this page." }),
      ]);
    });
    show([
      el("h1", { text: cfg.title }),
      el("p", { id: "consent-text", text: cfg.consent }),
      el("label", { class: "check", for: "consent-agree" }, [box, el("span", { text: "I have read the above and agree to take part." })]),
      el("div", { class: "actions" }, [go, no]),
    ]);
  }

  function preload(trials) {
    var urls = {};
    trials.forEach(function (t) { t.stimuli.forEach(function (u) { urls[u] = true; }); });
    return Promise.all(Object.keys(urls).map(function (url) {
      return new Promise(function (resolve, reject) {
        var img = new Image();
        img.onload = function () { resolve(url); };
        img.onerror = function () { reject(new Error("cannot load " + url)); };
        img.src = url;
      });
    }));
  }

  function instructions() {
    window.addEventListener("beforeunload", leaveWarning);
    var pick = pickRow();
    state.row = rows[pick.index];
    state.assignment = pick.how;
    var start = el("button", { class: "primary", id: "start", disabled: true, text: "Loading\u2026" });
    var status = el("p", { class: "note", id: "load-status" });
    start.addEventListener("click", function () { runTrial(0); });
    show([
      el("h1", { text: "Instructions" }),
      el("p", { id: "instructions-text", text: cfg.instructions }),
      status,
      el("div", { class: "actions" }, [start]),
    ]);
    preload(state.row.trials).then(function () {
      start.disabled = false;
      start.textContent = "Start";
    }, function (err) {
      status.className = "error";
      status.textContent = "The images could not be loaded (" + err.message + "). Please reload the page.";
    });
  }

  function baseRecord(trial, index) {
    return {
      participant_id: state.participant_id,
      session_id: state.session_id,
      study_id: state.study_id,
      study: cfg.kind,
      list_id: state.row.list_id,
      trial: index,
      word: trial.word,
      is_attention_check: !!trial.is_attention_check,
      attention_pass: "",
      app_version: cfg.app_version,
      seed: cfg.seed,
    };
  }

  function header(trial, index) {
    var total = state.row.trials.length;
    var nodes = [el("p", { class: "progress", id: "progress", text: "Trial " + (index + 1) + " of " + total })];
    if (trial.is_attention_check && trial.instruction) {
      nodes.push(el("p", { class: "instruction", id: "check-instruction", text: trial.instruction }));
    }
    return nodes;
  }

  function runTrial(index) {
    state.index = index;
    if (index >= state.row.trials.length) { finish(); return; }
    var trial = state.row.trials[index];
    if (cfg.kind === "turing") turingTrial(trial, index);
    else readabilityTrial(trial, index);
  }

  function turingTrial(trial, index) {
    var t0 = performance.now();
    var chosen = null, rt = null, confidence = null;
    var next = el("button", { class: "primary", id: "next", disabled: true, text: "Next" });
    function update() { next.disabled = chosen === null || confidence === null; }
    var options = trial.stimuli.map(function (src, i) {
      var button = el("button", { type: "button", class: "option", "data-option": i + 1, "aria-pressed": "false" }, [
        el("span", { class: "label", text: String(i + 1) }),
        el("img", { src: src, alt: "sample " + (i + 1), draggable: "false" }),
      ]);
      button.addEventListener("click", function () {
        chosen = i;
        rt = performance.now() - t0;
        options.forEach(function (b, j) { b.setAttribute("aria-pressed", j === i ? "true" : "false"); });
        update();
      });
      return button;
    });
    var scale = cfg.confidence_labels.map(function (label, i) {
      var button = el("button", { type: "button", "data-confidence": i + 1, "aria-pressed": "false", text: (i + 1) + " \u2013 " + label });
      button.addEventListener("click", function () {
        confidence = i + 1;
        scale.forEach(function (b, j) { b.setAttribute("aria-pressed", j === i ? "true" : "false"); });
        update();
      });
      return button;
    });
    next.addEventListener("click", function () {
      if (chosen === null || confidence === null) return;
      var record = baseRecord(trial, index);
      record.robot_index = trial.robot_index;
      record.chosen_index = chosen;
      record.chose_robot = chosen === trial.robot_index;
      record.confidence = confidence;
      record.rt_ms = Math.round(rt);
      record.timestamp = new Date().toISOString();
      if (trial.is_attention_check) {
        var wanted = trial.expect.confidence;
        record.attention_pass = chosen === trial.expect.chosen_index &&
          (wanted === undefined || wanted === null || confidence === wanted);
      }
      state.records.push(record);
      runTrial(index + 1);
    });
    show(header(trial, index).concat([
      el("h2", { text: "Which sample of \u201c" + trial.word + "\u201d did the robot write?" }),
      el("div", { class: "options", role: "group", "aria-label": "samples" }, options),
      el("div", { class: "respond" }, [
        el("fieldset", { class: "confidence" }, [
          el("legend", { text: "How confident are you?" }),
          el("div", { class: "scale" }, scale),
        ]),
        el("div", { class: "actions" }, [next]),
      ]),
    ]), "trial-turing");
  }

  function readabilityTrial(trial, index) {
    var t0 = performance.now();
    var input = el("input", {
      type: "text", id: "answer", autocomplete: "off", autocapitalize: "off",
      autocorrect: "off", spellcheck: "false", "aria-label": "the word you read",
    });
    var next = el("button", { class: "primary", id: "next", disabled: true, text: "Next" });
    var cannot = el("button", { id: "cannot-read", text: "I can\u2019t read it" });
    var done = false;
    function submit(text) {
      if (done) return;
      done = true;
      var record = baseRecord(trial, index);
      record.writer = trial.writer;
      record.typed_text = text;
      record.correct = text !== "" && normalise(text) === normalise(trial.word);
      record.rt_ms = Math.round(performance.now() - t0);
      record.timestamp = new Date().toISOString();
      if (trial.is_attention_check) {
        record.attention_pass = normalise(text) === normalise(trial.expect.typed_text);
      }
      state.records.push(record);
      runTrial(index + 1);
    }
    input.addEventListener("input", function () { next.disabled = input.value.trim() === ""; });
    input.addEventListener("keydown", function (event) {
      if (event.key === "Enter" && input.value.trim() !== "") submit(input.value.trim());
    });
    next.addEventListener("click", function () { if (input.value.trim() !== "") submit(input.value.trim()); });
    cannot.addEventListener("click", function () { submit(""); });
    show(header(trial, index).concat([
      el("h2", { text: "Which word is written here?" }),
      el("div", { class: "single" }, [el("img", { src: trial.stimuli[0], alt: "handwritten word", draggable: "false" })]),
      el("p", {}, [input]),
      el("div", { class: "actions" }, [next, cannot]),
    ]), "trial-readability");
    input.focus();
  }

  // ------------------------------------------------------------------ saving and completion
  function fileName() {
    var who = state.participant_id.replace(/[^A-Za-z0-9_-]/g, "_").slice(0, 64);
    return (cfg.pilot ? "PILOT_" : "") + cfg.name + "_" + who + "_" + page.fileStamp() + ".csv";
  }

  function download(csv) {
    page.download(csv, "text/csv;charset=utf-8", fileName());
  }

  function finish() {
    state.finished = true;
    var csv = window.PRGStudy.csv();
    var status = el("p", { class: "note", id: "save-status", text: "Saving your answers\u2026" });
    var code = cfg.completion.code;
    var nodes = [
      el("h1", { text: "Thank you!" }),
      el("p", { id: "end-text", text: "You have finished the study." }),
      status,
      el("p", {}, ["Your completion code: ", el("span", { class: "code", id: "completion-code", text: code })]),
    ];
    var actions = el("div", { class: "actions" });
    if (cfg.save.download) {
      var again = el("button", { id: "download", text: "Download my answers (CSV)" });
      again.addEventListener("click", function () { download(csv); });
      actions.appendChild(again);
    }
    var url = cfg.completion.redirect_url;
    if (url) {
      actions.appendChild(el("a", { class: "button primary", id: "finish", href: url, text: "Finish and return to Prolific" }));
    }
    nodes.push(actions);
    show(nodes);
    window.removeEventListener("beforeunload", leaveWarning);
    if (cfg.save.download) download(csv);
    var saving = cfg.save.post_url ? page.postText(cfg.save.post_url, csv, 3) : Promise.resolve();
    saving.then(function () {
      state.saved = true;
      status.textContent = cfg.save.post_url ? "Your answers were saved." : "";
      if (url) {
        status.textContent += " Returning you to Prolific\u2026";
        setTimeout(function () { window.location.assign(url); }, cfg.completion.redirect_delay_ms);
      }
    }, function (err) {
      state.saved = false;
      status.className = "error";
      status.textContent = "Your answers could not be sent (" + err.message + "). Please download " +
        "them with the button below, keep the file, and contact the researchers.";
      if (!cfg.save.download) {
        var rescue = el("button", { id: "download", text: "Download my answers (CSV)" });
        rescue.addEventListener("click", function () { download(csv); });
        actions.insertBefore(rescue, actions.firstChild);
      }
    });
  }

  // ------------------------------------------------------------------ start
  if (!cfg || !list) {
    app.textContent = "This page is missing config.js or trials.js; rebuild it with prg-study build.";
  } else if (!cfg.ready || rows.length === 0) {
    notReady();
  } else {
    consent();
  }
})();
