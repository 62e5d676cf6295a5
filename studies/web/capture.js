/*
 * prg-study capture page: records a writer's pen trajectories, one word at a time, the word
 * written in one continuous stroke (the paper's group 1), then, with delayed strokes on, the dots
 * of its i's and j's and the bars of its t's and f's. No dependencies but common.js; runs from
 * file://.
 *
 * Reads window.PRG_CAPTURE_CONFIG (config.js, written by `prg-study build`): words, canvas size,
 * on_lift ("restart": lifting the pen clears the word and the writer starts again; "flag": the
 * extra strokes are kept and the sample is marked lifted), delayed_strokes (true: a small stroke
 * after the word is a dot or a bar, not a lift), delayed_max_size, post_url, app_version.
 * URL parameter: writer=ID fills in the writer id.
 *
 * Saves one JSON document per writer (downloaded, and POSTed as text/plain when post_url
 * is set):
 *   { "schema": "prg.handwriting_capture", "version": 1, "writer_id": "w01",
 *     "study": ..., "app_version": ..., "started_at": ISO, "finished_at": ISO, "user_agent": ...,
 *     "on_lift": "restart", "delayed_strokes": true, "delayed_max_size": 0.35,
 *     "canvas": { "width": 900, "height": 300, "units": "css_px", "y_down": true,
 *                 "device_pixel_ratio": 2, "baseline_y": 195 },
 *     "samples": [ { "word": "cat", "strokes": [[[x, y, t_ms, pressure], ...], ...],
 *                    "delayed": [1], "lifted": false, "restarts": 0, "skipped": false,
 *                    "pointer_type": "pen", "started_at": ISO, "duration_ms": 1830.4 }, ... ] }
 * "My style" (URL parameter style=1, or style=LETTERS such as style=abdegh): the writer writes
 * single letters instead of the study's words (STYLE_LETTERS by default), each in one stroke, and
 * downloads style_<id>_<time>.json (the same schema, "purpose": "style"; never posted): the
 * style file of `prg-write style=FILE`, which writes any word in that hand.
 * x, y in canvas CSS pixels (y down), t_ms from the sample's first pen-down. "delayed" lists the
 * strokes (by index, never 0: the first stroke is the word) kept as delayed strokes; files
 * written before it have no "delayed" and read as having none.
 */
(function () {
  "use strict";

  var cfg = window.PRG_CAPTURE_CONFIG;
  var app = document.getElementById("app");
  var page = window.PRGPage;  // common.js
  var el = page.el;
  var WRITER_RE = /^[A-Za-z0-9_-]{1,64}$/;

  function show(nodes) { page.show(app, nodes); }

  var params = new URLSearchParams(window.location.search);
  // "my style": a few single letters, each in one stroke (see the header)
  var STYLE_LETTERS = "abdeghklmnorstw";
  var styleParam = params.get("style");
  var styleMode = styleParam !== null && styleParam !== "0";
  var styleLetters = styleMode && /^[0-9A-Za-z]{1,62}$/.test(styleParam) ? styleParam : STYLE_LETTERS;
  var words = cfg ? (styleMode ? styleLetters.split("") : cfg.words) : [];
  var state = {
    writer_id: null,
    started_at: null,
    index: 0,
    samples: [],
    document: null,
    posted: null,
  };
  window.PRGCapture = { state: state, config: cfg };

  function baselineY() { return Math.round(cfg.canvas_height * 0.65); }

  // Delayed strokes on: after the word (the first stroke), a stroke is a dot or a bar when its
  // bounding box is no taller than delayed_max_size (e.g. 0.35) times the first stroke's height
  // and no wider than twice that (a bar is flat but can be long); a larger one is a pen lift
  // (on_lift decides what happens). A letter written after a lift is at least as tall as the
  // x-height, half or more of a word's height, so it does not pass as a mark.
  function delayedOn() { return !styleMode && cfg.delayed_strokes === true; }
  function maxDelayedSize() {
    var f = Number(cfg.delayed_max_size);
    return f > 0 ? f : 0.35;
  }
  function box(points) {
    var xs = points.map(function (p) { return p[0]; });
    var ys = points.map(function (p) { return p[1]; });
    return {
      width: Math.max.apply(null, xs) - Math.min.apply(null, xs),
      height: Math.max.apply(null, ys) - Math.min.apply(null, ys),
    };
  }
  function isDelayedStroke(first, later) {
    var limit = maxDelayedSize() * box(first).height;
    var b = box(later);
    return b.width <= 2 * limit && b.height <= limit;
  }

  function intro() {
    var input = el("input", { type: "text", id: "writer-id", autocomplete: "off", spellcheck: "false", "aria-label": "writer id" });
    input.value = params.get("writer") || "";
    var begin = el("button", { class: "primary", id: "begin", text: "Begin" });
    var hint = el("p", { class: "note", id: "writer-hint" });
    function check() {
      var v = input.value.trim();
      var ok = WRITER_RE.test(v) && v.toLowerCase() !== "robot";
      begin.disabled = !ok;
      hint.textContent = ok || v === "" ? "" : "Use letters, digits, - or _ (up to 64), not \u201crobot\u201d.";
      return ok;
    }
    input.addEventListener("input", check);
    begin.addEventListener("click", function () {
      if (!check()) return;
      state.writer_id = input.value.trim();
      state.started_at = new Date().toISOString();
      word(0);
    });
    check();
    show([
      el("h1", { text: styleMode ? "My style: a few letters in your hand" : "Handwriting recording" }),
      el("p", { id: "intro-text", text: styleMode
        ? "You will see " + words.length + " letters, one at a time. Write each letter as you usually do, in one " +
          "continuous movement (leave out the dots of i and j). At the end you download your style file: " +
          "prg-write style=FILE writes any word in your hand."
        : "You will see " + words.length + " words, one at a time. Write each word in cursive handwriting " +
        "in the box, in one continuous movement: do not lift the pen (or finger, or mouse button) until the word is finished. " +
        (delayedOn()
          ? "Then dot the i's and j's and cross the t's and f's, as you usually do; keep the dots and bars small."
          : "Dots and crossings are not needed.") }),
      el("p", { text: "Use a pen or stylus if you have one. Write at your usual size along the grey line." }),
      el("p", {}, [el("label", { for: "writer-id", text: "Writer id: " }), input]),
      hint,
      el("div", { class: "actions" }, [begin]),
    ]);
    if (!input.value) input.focus();
  }

  function word(index) {
    state.index = index;
    if (index >= words.length) { finish(); return; }
    var text = words[index];
    var dpr = window.devicePixelRatio || 1;
    var pad = el("canvas", { id: "pad", width: Math.round(cfg.canvas_width * dpr), height: Math.round(cfg.canvas_height * dpr) });
    // shrinks on narrow screens, always keeping its shape: x and y stay on one scale
    pad.style.width = "100%";
    pad.style.maxWidth = cfg.canvas_width + "px";
    pad.style.aspectRatio = cfg.canvas_width + " / " + cfg.canvas_height;
    var ctx = pad.getContext("2d");
    var message = el("p", { class: "note", id: "message" });
    var next = el("button", { class: "primary", id: "next", disabled: true, text: index + 1 < words.length ? (styleMode ? "Next letter" : "Next word") : "Finish" });
    var clear = el("button", { id: "clear", text: "Clear" });
    var skip = el("button", { id: "skip", text: styleMode ? "Skip this letter" : "Skip this word" });
    var sample = null;
    var drawing = null;  // the stroke being drawn

    function reset() {
      sample = {
        word: text, strokes: [], delayed: [], lifted: false, restarts: sample ? sample.restarts : 0,
        skipped: false, pointer_type: null, started_at: null, duration_ms: 0, t0: null,
      };
      drawing = null;
      ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
      ctx.clearRect(0, 0, cfg.canvas_width, cfg.canvas_height);
      ctx.save();
      ctx.strokeStyle = "#c8c8c8";
      ctx.setLineDash([6, 6]);
      ctx.lineWidth = 1;
      ctx.beginPath();
      ctx.moveTo(10, baselineY() + 0.5);
      ctx.lineTo(cfg.canvas_width - 10, baselineY() + 0.5);
      ctx.stroke();
      ctx.restore();
      next.disabled = true;
    }

    function point(event) {
      var rect = pad.getBoundingClientRect();
      var x = (event.clientX - rect.left) * (cfg.canvas_width / rect.width);
      var y = (event.clientY - rect.top) * (cfg.canvas_height / rect.height);
      return [
        Math.round(x * 100) / 100,
        Math.round(y * 100) / 100,
        Math.round((event.timeStamp - sample.t0) * 10) / 10,
        Math.round((event.pressure || 0) * 1000) / 1000,
      ];
    }

    function ink(a, b) {
      ctx.strokeStyle = "#000";
      ctx.lineWidth = 3;
      ctx.lineCap = "round";
      ctx.lineJoin = "round";
      ctx.beginPath();
      ctx.moveTo(a[0], a[1]);
      ctx.lineTo(b[0], b[1]);
      ctx.stroke();
    }

    function add(event) {
      var p = point(event);
      var last = drawing.points[drawing.points.length - 1];
      if (last && last[0] === p[0] && last[1] === p[1]) return;
      if (last) ink(last, p);
      drawing.points.push(p);
    }

    pad.addEventListener("pointerdown", function (event) {
      if (event.pointerType === "mouse" && event.button !== 0) return;
      if (drawing) return;
      event.preventDefault();
      // the pen was lifted and put down again: without delayed strokes that is a lift now;
      // with them, whether the new stroke is a dot or bar is known when it ends (see up)
      if (sample.strokes.length > 0 && !delayedOn()) lifted();
      if (sample.t0 === null) {
        sample.t0 = event.timeStamp;
        sample.started_at = new Date().toISOString();
        sample.pointer_type = event.pointerType;
      }
      try { pad.setPointerCapture(event.pointerId); } catch (e) { /* synthetic events */ }
      drawing = { id: event.pointerId, points: [] };
      sample.strokes.push(drawing.points);
      add(event);
    });
    pad.addEventListener("pointermove", function (event) {
      if (!drawing || event.pointerId !== drawing.id) return;
      var events = event.getCoalescedEvents ? event.getCoalescedEvents() : [];
      (events.length ? events : [event]).forEach(add);
    });
    function lifted() {
      if (styleMode || cfg.on_lift === "restart") {  // a style letter is one stroke
        var restarts = sample.restarts + 1;
        reset();
        sample.restarts = restarts;
        message.className = "error";
        message.textContent = delayedOn()
          ? "The pen was lifted before the word was finished, so the word was cleared: please write it again in one movement, then add the dots and bars."
          : "The pen was lifted, so the word was cleared: please write it again in one movement.";
      } else {
        sample.lifted = true;
        message.className = "error";
        message.textContent = "The pen was lifted: this sample is marked. Clear it to start again.";
      }
    }

    function up(event) {
      if (!drawing || event.pointerId !== drawing.id) return;
      add(event);
      drawing = null;
      var index = sample.strokes.length - 1;
      var last = sample.strokes[index];
      if (delayedOn() && index > 0) {
        if (isDelayedStroke(sample.strokes[0], last)) {
          sample.delayed.push(index);
        } else {
          lifted();
          if (!sample.strokes.length) return;  // cleared: the word is written again
        }
      }
      sample.duration_ms = last[last.length - 1][2];
      next.disabled = false;
    }
    pad.addEventListener("pointerup", up);
    pad.addEventListener("pointercancel", up);

    clear.addEventListener("click", function () {
      reset();
      message.className = "note";
      message.textContent = "";
    });
    function keep(s) {
      delete s.t0;
      state.samples.push(s);
      word(index + 1);
    }
    next.addEventListener("click", function () { if (sample.strokes.length && !drawing) keep(sample); });
    skip.addEventListener("click", function () {
      reset();
      sample.skipped = true;
      keep(sample);
    });

    show([
      el("p", { class: "progress", id: "progress", text: (styleMode ? "Letter " : "Word ") + (index + 1) + " of " + words.length }),
      el("p", { id: "task", text: delayedOn()
        ? "Write this word in one movement, without lifting the pen; then dot the i's and j's and cross the t's and f's:"
        : "Write this word in one movement, without lifting the pen:" }),
      el("p", { class: "word", id: "word", text: text }),
      pad,
      message,
      el("div", { class: "actions" }, [next, clear, skip]),
    ]);
    reset();
  }

  function captureDocument() {
    return {
      schema: "prg.handwriting_capture",
      version: 1,
      writer_id: state.writer_id,
      study: cfg.study,
      app_version: cfg.app_version,
      started_at: state.started_at,
      finished_at: new Date().toISOString(),
      user_agent: navigator.userAgent,
      on_lift: styleMode ? "restart" : cfg.on_lift,
      delayed_strokes: delayedOn(),
      delayed_max_size: delayedOn() ? maxDelayedSize() : null,
      canvas: {
        width: cfg.canvas_width,
        height: cfg.canvas_height,
        units: "css_px",
        y_down: true,
        device_pixel_ratio: window.devicePixelRatio || 1,
        baseline_y: baselineY(),
      },
      samples: state.samples,
      purpose: styleMode ? "style" : "study",
    };
  }

  function download(text) {
    var prefix = styleMode ? "style_" : "capture_";
    page.download(text, "application/json", prefix + state.writer_id + "_" + page.fileStamp() + ".json");
  }

  function finish() {
    state.document = captureDocument();
    var text = JSON.stringify(state.document);
    var status = el("p", { class: "note", id: "done-status" });
    var again = el("button", { class: "primary", id: "download", text: styleMode ? "Download my style file (JSON)" : "Download the recording (JSON)" });
    again.addEventListener("click", function () { download(text); });
    var recorded = state.samples.filter(function (s) { return !s.skipped; }).length;
    show([
      el("h1", { text: "Thank you!" }),
      el("p", { id: "done-text", text: recorded + " of " + words.length + (styleMode ? " letters" : " words") + " were recorded for writer " + state.writer_id + "." +
        (styleMode ? " Write any word in this hand: prg-write text=WORD style=style_" + state.writer_id + "_....json" : "") }),
      status,
      el("div", { class: "actions" }, [again]),
    ]);
    download(text);
    if (cfg.post_url && !styleMode) {  // a style file stays with its writer
      status.textContent = "Sending\u2026";
      page.postText(cfg.post_url, text, 1)
        .then(function () {
          state.posted = true;
          status.textContent = "The recording was sent.";
        })
        .catch(function (err) {
          state.posted = false;
          status.className = "error";
          status.textContent = "The recording could not be sent (" + err.message + "); please keep the downloaded file.";
        });
    }
  }

  if (!cfg) app.textContent = "This page is missing config.js; rebuild it with prg-study build.";
  else intro();
})();
