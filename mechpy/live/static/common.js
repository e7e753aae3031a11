// mechpy live views: what every view uses (no imports; the view follows this text).

// An array packed by mechpy.live._page.pack: base64 of little-endian float64 (or float32).
function mpUnpack(b64, type) {
  const bin = atob(b64 || "");
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  return type === "f4" ? new Float32Array(bytes.buffer) : new Float64Array(bytes.buffer);
}

// A seeded uniform generator on [0, 1) (mulberry32): the same seeds in every browser.
function mpRandom(seed) {
  let a = (seed >>> 0) ^ 0x9e3779b9;
  return function () {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

// Frames per second over the last second.
function mpFps() {
  const times = [];
  return {
    tick(now) {
      times.push(now);
      while (times.length && now - times[0] > 1000) times.shift();
    },
    value() {
      if (times.length < 2) return 0;
      return (1000 * (times.length - 1)) / (times[times.length - 1] - times[0]);
    },
  };
}

// The page's interface for tests and automation: window.mechpyLive is the view rendered
// last, window.mechpyLives every view of the page in the order rendered.
function mpRegister(api) {
  window.mechpyLives = window.mechpyLives || [];
  window.mechpyLives.push(api);
  window.mechpyLive = api;
  return () => {
    window.mechpyLives = (window.mechpyLives || []).filter((a) => a !== api);
    if (window.mechpyLive === api) window.mechpyLive = window.mechpyLives[window.mechpyLives.length - 1];
  };
}

// An element with attributes and children.
function mpEl(tag, attrs, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) {
    if (k === "style") e.style.cssText = v;
    else if (k.startsWith("on")) e.addEventListener(k.slice(2), v);
    else e.setAttribute(k, v);
  }
  for (const c of children) e.append(c);
  return e;
}

// The width of a view that follows the page: its box is `width:100%` of the container with
// `max` px at most (the view's width= in Python), so that a view never runs past the column
// of a docs page or a notebook; the canvas is sized to the box in device-independent pixels.
// onResize(w) when the box's width changes (a window or a column resized); stop() ends that.
function mpFollowWidth(box, max, onResize) {
  const fit = () => Math.max(64, Math.min(max, Math.floor(box.clientWidth || max)));
  let w = fit();
  const ro = typeof ResizeObserver === "function" ? new ResizeObserver(() => {
    const v = fit();
    if (v !== w) { w = v; onResize(v); }
  }) : null;
  if (ro) ro.observe(box);
  return {width: w, stop: () => { if (ro) ro.disconnect(); }};
}

// A labelled slider: onInput(value) on every move.
function mpSlider(label, min, max, value, step, onInput) {
  const out = mpEl("span", {style: "display:inline-block;min-width:5em;font-variant-numeric:tabular-nums"});
  const fmt = (v) => Number(v).toPrecision(4);
  out.textContent = fmt(value);
  const input = mpEl("input", {type: "range", min: String(min), max: String(max),
    step: String(step), value: String(value), "aria-label": label});
  input.addEventListener("input", () => { out.textContent = fmt(input.value); onInput(Number(input.value)); });
  const row = mpEl("label", {style: "display:flex;gap:.5em;align-items:center;font-size:13px"},
    mpEl("span", {style: "min-width:7em"}, label), input, out);
  row.input = input;
  row.set = (v) => { input.value = String(v); out.textContent = fmt(v); };
  return row;
}

// A button.
function mpButton(text, onClick) {
  return mpEl("button", {type: "button", onclick: onClick,
    style: "font-size:13px;padding:2px 10px;margin-right:4px"}, text);
}

// erf and erfc in double precision for a printed field, the phase portrait's and a
// simulating page's (JavaScript's Math has neither; mechpy.live._field prints them as
// mp.erf, mp.erfc): erf below 2.5 by its series
// exp(-a^2) sum (2a^2)^n a / (2n+1)!! (positive terms), erfc by 1 - erf below 2 and by its
// continued fraction (80 terms) from 2 on; exp(-a^2) with a^2 split (Dekker) so that its
// rounding does not count a^2 times.
function mpExpMsq(a) {
  const c = 134217729 * a, ah = c - (c - a), al = a - ah;
  return Math.exp(-ah * ah) * Math.exp(-al * (ah + a));
}
function mpErfSeries(a) {
  let term = a, sum = a;
  const z = 2 * a * a;
  for (let n = 1; n < 200 && term > 1e-17 * sum; n++) { term *= z / (2 * n + 1); sum += term; }
  return 1.1283791670955126 * mpExpMsq(a) * sum;
}
function mpErfcPos(a) {
  if (a < 2) return 1 - mpErfSeries(a);
  if (a > 27.3) return 0;
  let f = a;
  for (let n = 80; n > 0; n--) f = a + 0.5 * n / f;
  return mpExpMsq(a) / (1.7724538509055160 * f);
}
const MP_JS_MATH = {
  erf(x) {
    const a = Math.abs(x), r = a < 2.5 ? mpErfSeries(a) : 1 - mpErfcPos(a);
    return x < 0 ? -r : r;
  },
  erfc(x) { return x < 0 ? 2 - mpErfcPos(-x) : mpErfcPos(x); },
};

// viridis, as 9 stops: colour of s in [0, 1].
const MP_VIRIDIS = [[68, 1, 84], [72, 40, 120], [62, 74, 137], [49, 104, 142], [38, 130, 142],
  [31, 158, 137], [53, 183, 121], [109, 205, 89], [253, 231, 37]];
function mpViridis(s) {
  const x = Math.min(Math.max(s, 0), 1) * (MP_VIRIDIS.length - 1);
  const i = Math.min(Math.floor(x), MP_VIRIDIS.length - 2), f = x - i;
  const a = MP_VIRIDIS[i], b = MP_VIRIDIS[i + 1];
  return `rgb(${a.map((v, k) => Math.round(v + f * (b[k] - v))).join(",")})`;
}

// three.js (npm three@0.180.0, vendored) loaded from blob URLs: {THREE, OrbitControls}.
let mpThreePromise = null;
function mpThree() {
  if (mpThreePromise) return mpThreePromise;
  mpThreePromise = (async () => {
    const blob = (text) => URL.createObjectURL(new Blob([text], {type: "text/javascript"}));
    const core = blob(MP_THREE_SOURCES["three.core.min.js"]);
    const module = blob(MP_THREE_SOURCES["three.module.min.js"].split("./three.core.min.js").join(core));
    const orbit = blob(MP_THREE_SOURCES["OrbitControls.js"].split("./three.module.min.js").join(module));
    const THREE = await import(module);
    const {OrbitControls} = await import(orbit);
    return {THREE, OrbitControls};
  })();
  return mpThreePromise;
}
