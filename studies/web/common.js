/*
 * prg-study: what the questionnaire page (study.js) and the capture page (capture.js) share, as
 * window.PRGPage: building elements, showing a screen, saving a file, POSTing text.
 * No dependencies; loaded before the page's own script (runs from file://).
 */
window.PRGPage = (function () {
  "use strict";

  // An element with attributes ("text": its text, "onclick": a click handler; null, undefined
  // and false leave an attribute out, true sets it empty) and children (nodes or strings).
  function el(tag, attrs, children) {
    var node = document.createElement(tag);
    Object.keys(attrs || {}).forEach(function (key) {
      var value = attrs[key];
      if (value === null || value === undefined || value === false) return;
      if (key === "text") node.textContent = value;
      else if (key === "onclick") node.addEventListener("click", value);
      else node.setAttribute(key, value === true ? "" : String(value));
    });
    (children || []).forEach(function (child) {
      node.appendChild(typeof child === "string" ? document.createTextNode(child) : child);
    });
    return node;
  }

  // Replace what `app` shows with `nodes`.
  function show(app, nodes) {
    app.textContent = "";
    nodes.forEach(function (n) { app.appendChild(n); });
  }

  // The time now for a file name: 20250301T101500 (UTC).
  function fileStamp() {
    return new Date().toISOString().replace(/[-:]/g, "").replace(/\..*$/, "");
  }

  // Offer `text` as a file download named `name`.
  function download(text, type, name) {
    var blob = new Blob([text], { type: type });
    var a = el("a", { href: URL.createObjectURL(blob), download: name });
    document.body.appendChild(a);
    a.click();
    setTimeout(function () { URL.revokeObjectURL(a.href); a.remove(); }, 60000);
  }

  // POST `text` as text/plain (a simple request: no CORS preflight), up to `tries` times one
  // second apart; rejects with the last error.
  function postText(url, text, tries) {
    return fetch(url, {
      method: "POST",
      headers: { "Content-Type": "text/plain;charset=utf-8" },
      body: text,
    }).then(function (response) {
      if (!response.ok) throw new Error("HTTP " + response.status);
    }).catch(function (err) {
      if (tries > 1) {
        return new Promise(function (r) { setTimeout(r, 1000); }).then(function () { return postText(url, text, tries - 1); });
      }
      throw err;
    });
  }

  return { el: el, show: show, fileStamp: fileStamp, download: download, postText: postText };
})();
