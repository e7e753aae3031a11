// mechpy.live.animate: the motion of a solution in 3D (three.js).  Every frame is computed
// in Python (spec.pos: the bodies' places, spec.rot: the body-to-space matrix of a top or a
// rigid body); the page places the bodies, draws rods, trails and fixed lines, and plays.
// A page that simulates (spec.sim: mp.live.animate's params=, y0=) computes the places itself
// (static/simulate.js, loaded before this file) and again when a slider moves.

function mpMotionFrame(THREE, spec, sim) {
  const n = spec.n, nb = spec.nb;
  // a page that simulates (static/simulate.js) computes the places itself, into sim.P
  const P = sim ? sim.P : mpUnpack(spec.pos), R = spec.rot ? mpUnpack(spec.rot) : null;
  const m4 = new THREE.Matrix4(), q = new THREE.Quaternion();
  // the places of the bodies at frame k (world coordinates, the system's units)
  return function (k, out) {
    if (R) {
      const r = R.subarray(9 * k, 9 * k + 9);
      m4.set(r[0], r[1], r[2], 0, r[3], r[4], r[5], 0, r[6], r[7], r[8], 0, 0, 0, 0, 1);
      q.setFromRotationMatrix(m4);
    }
    for (let i = 0; i < nb; i++) {
      const b = spec.bodies[i];
      if (R && b.local) out[i].set(b.local[0], b.local[1], b.local[2]).applyQuaternion(q);
      else out[i].set(P[3 * (k * nb + i)], P[3 * (k * nb + i) + 1], P[3 * (k * nb + i) + 2]);
    }
    return R ? q : null;
  };
}

// The time series of plots= under the 3D view: one panel a series (its curve, axes, ticks and
// name), a cursor (a vertical line) at the shown frame's time.  Each panel's canvas is drawn
// once a width; the cursor is a positioned element moved by show(k).  The panel's plot area
// (CSS px from its left) and time range are its data-left, data-width, data-t0, data-t1.
const MP_PLOT_H = 92, MP_PLOT_FONT = "11px sans-serif";

// about n "nice" ticks over [lo, hi] (steps 1, 2, 5 x 10^k) and the decimals they need
function mpTicks(lo, hi, n) {
  const raw = (hi - lo) / n, mag = Math.pow(10, Math.floor(Math.log10(raw)));
  const step = [1, 2, 5, 10].map((f) => f * mag).find((s) => s >= raw) || 10 * mag;
  const out = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + 1e-9 * step; v += step) out.push(v);
  if (out.length < 2 && n < 64) return mpTicks(lo, hi, 2 * n);     // at least two
  return {ticks: out, decimals: Math.max(0, -Math.floor(Math.log10(step) + 1e-9))};
}

function mpPlotPanels(spec, T, maxWidth, onSeek, sim) {
  const box = mpEl("div", {class: "mechpy-plots", style: `width:100%;max-width:${maxWidth}px`});
  const panels = (spec.plots || []).map((p, i) => {
    const y = sim ? sim.S[i] : mpUnpack(p.y);       // a page that simulates: its own series
    const canvas = mpEl("canvas", {style: "display:block"});
    const cursor = mpEl("div", {class: "mechpy-cursor", style: "position:absolute;width:0;"
      + "border-left:2px solid #d62728;pointer-events:none"});
    const el = mpEl("div", {class: "mechpy-plot", "data-name": p.name, style: "position:relative;"
      + `height:${MP_PLOT_H}px;box-sizing:content-box;border:1px solid #ddd;border-top:none;`
      + "cursor:crosshair"},
      canvas, cursor);
    el.addEventListener("click", (ev) => {
      const r = el.getBoundingClientRect(), L = Number(el.dataset.left);
      const f = (ev.clientX - r.left - L) / Number(el.dataset.width);
      if (f >= 0 && f <= 1) onSeek(Math.round(f * (T.length - 1)));
    });
    box.append(el);
    return {p, y, canvas, cursor, el, L: 0, W: 0, top: 0, h: 0};
  });
  const t0 = T[0], t1 = T[T.length - 1];
  // draw every panel at width w (CSS px)
  function draw(w) {
    const dpr = Math.min(window.devicePixelRatio || 1, 2);
    // the ticks of each panel, then one left margin for all: the time axes line up
    const measure = document.createElement("canvas").getContext("2d");
    measure.font = MP_PLOT_FONT;
    let L = 0;
    for (const P of panels) {
      let lo = Infinity, hi = -Infinity;
      for (const v of P.y) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
      const pad = hi > lo ? 0.06 * (hi - lo) : Math.max(Math.abs(hi) * 1e-6, 1e-12);
      P.lo = lo - pad;
      P.hi = hi + pad;
      P.yt = mpTicks(P.lo, P.hi, 4);
      P.ylab = P.yt.ticks.map((v) => v.toFixed(Math.min(P.yt.decimals, 15)));
      L = Math.max(L, 14 + Math.max(...P.ylab.map((t) => measure.measureText(t).width)));
    }
    for (const P of panels) {
      const {canvas, y, p} = P;
      canvas.width = Math.round(w * dpr);
      canvas.height = Math.round(MP_PLOT_H * dpr);
      canvas.style.width = `${w}px`;
      canvas.style.height = `${MP_PLOT_H}px`;
      const g = canvas.getContext("2d");
      g.setTransform(dpr, 0, 0, dpr, 0, 0);
      g.clearRect(0, 0, w, MP_PLOT_H);
      g.font = MP_PLOT_FONT;
      const {lo, hi, yt, ylab} = P, tt = mpTicks(Math.min(t0, t1), Math.max(t0, t1), 8), R = 12;
      const top = 15, h = MP_PLOT_H - top - 18, W = Math.max(10, w - L - R);
      Object.assign(P, {L, W, top, h});
      const X = (t) => L + ((t - t0) / (t1 - t0 || 1)) * W;
      const Yp = (v) => top + ((hi - v) / (hi - lo)) * h;
      // axes, grid and ticks
      g.strokeStyle = "#e4e4e4";
      g.fillStyle = "#333";
      g.lineWidth = 1;
      g.textAlign = "right";
      g.textBaseline = "middle";
      yt.ticks.forEach((v, i) => {
        g.beginPath(); g.moveTo(L, Yp(v)); g.lineTo(L + W, Yp(v)); g.stroke();
        g.fillText(ylab[i], L - 5, Yp(v));
      });
      g.textAlign = "center";
      g.textBaseline = "top";
      for (const v of tt.ticks) {
        g.beginPath(); g.moveTo(X(v), top); g.lineTo(X(v), top + h); g.stroke();
        g.fillText(v.toFixed(tt.decimals), X(v), top + h + 4);
      }
      g.strokeStyle = "#888";
      g.strokeRect(L, top, W, h);
      // the name (legend) and the time axis's
      g.textAlign = "left";
      g.textBaseline = "middle";
      g.fillStyle = p.color;
      g.fillRect(L, 6, 16, 3);
      g.fillStyle = "#222";
      g.fillText(p.name, L + 22, 7);
      g.textAlign = "right";
      g.fillText("t", L + W, 7);
      // the series, one vertex a frame
      g.strokeStyle = p.color;
      g.lineWidth = 1.6;
      g.beginPath();
      for (let k = 0; k < y.length; k++) {
        if (k) g.lineTo(X(T[k]), Yp(y[k])); else g.moveTo(X(T[k]), Yp(y[k]));
      }
      g.stroke();
      Object.assign(P.el.dataset, {left: String(L), width: String(W), t0: String(t0),
        t1: String(t1)});
      P.cursor.style.top = `${top}px`;
      P.cursor.style.height = `${h}px`;
    }
  }
  // the cursor at frame k's time (its centre on the time's abscissa)
  function at(k) {
    for (const P of panels) {
      const x = P.L + ((T[k] - t0) / (t1 - t0 || 1)) * P.W;
      P.cursor.style.left = `${x - 1}px`;
      P.cursor.dataset.t = String(T[k]);
      P.cursor.dataset.x = String(x);
    }
  }
  const byName = new Map(panels.map((P) => [P.p.name, P.y]));
  return {box, draw, at, series: byName};
}

export default {
  async render({model, el}) {
    const spec = model.get("spec");
    const {THREE, OrbitControls} = await mpThree();
    const n = spec.n, nb = spec.nb, ext = spec.extent;
    const T = mpUnpack(spec.t);
    const sim = spec.sim ? mpSimulation(spec) : null;
    if (sim) sim.run();
    const place = mpMotionFrame(THREE, spec, sim);

    // ---- page
    // the view takes its container's width, 960 px at most (mpFollowWidth), 0.62 of it high
    // (0.46 above plots, so that the view and three panels fit a screen)
    const MAXW = 960, aspect = (spec.plots || []).length ? 0.46 : 0.62;
    let W = Math.max(64, Math.min(el.clientWidth || 760, MAXW)), H = Math.round(aspect * W);
    const renderer = new THREE.WebGLRenderer({antialias: true});
    renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
    renderer.setSize(W, H);
    renderer.domElement.style.display = "block";
    renderer.setClearColor(0xffffff, 1);
    const clock = mpEl("div", {style: "position:absolute;right:8px;top:6px;font:13px monospace;"
      + "background:rgba(255,255,255,.8);padding:1px 4px"});
    const legend = mpEl("div", {style: "position:absolute;left:8px;top:6px;font-size:12px;"
      + "background:rgba(255,255,255,.8);padding:2px 4px;max-width:60%"});
    const stage = mpEl("div", {style: `position:relative;width:100%;max-width:${MAXW}px;`
      + `height:${H}px;box-sizing:border-box;border:1px solid #ddd`}, renderer.domElement, clock, legend,
      ...(sim ? [sim.message] : []));
    const title = mpEl("div", {style: "font-size:13px;margin:2px 0 4px"}, spec.title);

    // ---- scene
    const scene = new THREE.Scene();
    scene.add(new THREE.HemisphereLight(0xffffff, 0x667788, 2.2));
    const sun = new THREE.DirectionalLight(0xffffff, 1.6);
    sun.position.set(spec.up[0] + 0.6, spec.up[1] + 0.8, spec.up[2] + 1.0).multiplyScalar(10 * ext);
    scene.add(sun);
    const color = (c) => new THREE.Color(c);
    const solidMat = (c) => new THREE.MeshStandardMaterial({color: color(c), roughness: 0.55,
      metalness: 0.05});
    const V = (a) => new THREE.Vector3(a[0], a[1], a[2]);

    // bodies
    const where = Array.from({length: nb}, () => new THREE.Vector3());
    // a body with a size is a solid of shapes= or of its inertia (kind "bodies"), its
    // geometry in the body's frame (turned to its principal axes by b.axes, row-major)
    function solidGeometry(b) {
      const s = b.size;
      let g;
      if (b.shape === "box") g = new THREE.BoxGeometry(s[0], s[1], s[2]);
      else if (b.shape === "cylinder") g = new THREE.CylinderGeometry(s[0], s[0], s[1], 40);
      else if (b.shape === "cone") g = new THREE.ConeGeometry(s[0], s[1], 40);
      else if (b.shape === "torus") {
        g = new THREE.TorusGeometry(s[0], s[1], 16, 64);
        g.rotateX(Math.PI / 2);                  // its axis: the body's y, as a cylinder's
      } else g = new THREE.SphereGeometry(s[0], 28, 18);
      if (b.axes) {
        const a = b.axes;
        g.applyMatrix4(new THREE.Matrix4().set(a[0], a[1], a[2], 0, a[3], a[4], a[5], 0,
          a[6], a[7], a[8], 0, 0, 0, 0, 1));
      }
      return g;
    }
    const meshes = spec.bodies.map((b) => {
      let g;
      if (b.size) {
        const mesh = new THREE.Mesh(solidGeometry(b), new THREE.MeshStandardMaterial({
          color: color(b.color), roughness: 0.55, metalness: 0.05, transparent: b.shape !== "sphere",
          opacity: b.shape === "sphere" ? 1 : 0.8}));
        if (b.shape !== "sphere") mesh.add(new THREE.LineSegments(
          new THREE.EdgesGeometry(mesh.geometry, 30), new THREE.LineBasicMaterial({color: 0x555555})));
        scene.add(mesh);
        return mesh;
      }
      if (b.shape === "cube") g = new THREE.BoxGeometry(2 * b.radius, 2 * b.radius, 2 * b.radius);
      else if (b.shape === "cone") g = new THREE.ConeGeometry(b.radius, 3 * b.radius, 20);
      else g = new THREE.SphereGeometry(b.radius, 28, 18);
      const mesh = new THREE.Mesh(g, solidMat(b.color));
      scene.add(mesh);
      return mesh;
    });
    // rods: thin cylinders between two bodies or a body and a fixed point, thinner than the
    // smallest body (a chain's masses show on its springs)
    const Y = new THREE.Vector3(0, 1, 0), tmp = new THREE.Vector3();
    const rodR = Math.min(0.008 * ext, 0.3 * Math.min(...spec.bodies.map((b) => b.radius)));
    const rods = spec.rods.map(([a, b, c]) => {
      const mesh = new THREE.Mesh(new THREE.CylinderGeometry(rodR, rodR, 1, 12),
        solidMat(c));
      scene.add(mesh);
      return {a, b, mesh};
    });
    const end = (e) => (typeof e === "number" ? where[e] : V(e));
    function placeRod(r) {
      const a = end(r.a), b = end(r.b);
      tmp.subVectors(b, a);
      const len = tmp.length();
      r.mesh.visible = len > 0;
      if (!len) return;
      r.mesh.position.addVectors(a, b).multiplyScalar(0.5);
      r.mesh.quaternion.setFromUnitVectors(Y, tmp.divideScalar(len));
      r.mesh.scale.set(1, len, 1);
    }
    // fixed lines (nutation bounds, L, walls, compass)
    for (const ln of spec.lines) {
      const pts = mpUnpack(ln.pts);
      const g = new THREE.BufferGeometry();
      g.setAttribute("position", new THREE.BufferAttribute(new Float32Array(pts), 3));
      const mat = ln.dashed
        ? new THREE.LineDashedMaterial({color: color(ln.color), dashSize: 0.04 * ext,
          gapSize: 0.025 * ext})
        : new THREE.LineBasicMaterial({color: color(ln.color)});
      const line = new THREE.Line(g, mat);
      if (ln.dashed) line.computeLineDistances();
      scene.add(line);
    }
    // trails: the whole path of a body, drawn from the window's first frame to the shown one
    const trails = spec.trails.map((tr) => {
      const g = new THREE.BufferGeometry();
      g.setAttribute("position", new THREE.BufferAttribute(new Float32Array(3 * n), 3));
      const line = new THREE.Line(g, new THREE.LineBasicMaterial({color: color(tr.color),
        transparent: true, opacity: 0.85}));
      scene.add(line);
      return {line, window: tr.window, body: tr.body};
    });
    function fillTrails() {                    // again after a simulating page's re-run
      const all = where.map(() => new THREE.Vector3());
      const attrs = trails.map((tr) => tr.line.geometry.getAttribute("position"));
      for (let k = 0; k < n; k++) {            // each frame placed once for all the trails
        place(k, all);
        trails.forEach((tr, i) => all[tr.body].toArray(attrs[i].array, 3 * k));
      }
      trails.forEach((tr, i) => {
        attrs[i].needsUpdate = true;
        tr.line.geometry.computeBoundingSphere();
      });
    }
    fillTrails();
    // a solid turned by spec.rot: the top (a cone, apex at the pivot) or the box of the moments
    let solid = null;
    if (spec.solid) {
      solid = new THREE.Group();
      if (spec.solid.shape === "box") {
        const s = spec.solid.size;
        const g = new THREE.BoxGeometry(s[0], s[1], s[2]);
        const box = new THREE.Mesh(g, new THREE.MeshStandardMaterial({
          color: color(spec.solid.color), roughness: 0.6, transparent: true, opacity: 0.75}));
        solid.add(box, new THREE.LineSegments(new THREE.EdgesGeometry(g),
          new THREE.LineBasicMaterial({color: 0x555555})));
      } else {
        const l = spec.solid.l, h = (4 / 3) * l, r = 0.4 * l;
        const g = new THREE.ConeGeometry(r, h, 40);
        g.rotateX(-Math.PI / 2);
        // apex at the pivot, base up the axis: centroid at l, radius 0.3 l there
        g.translate(0, 0, h / 2);
        const body = new THREE.Mesh(g, new THREE.MeshStandardMaterial({
          color: color(spec.solid.color), roughness: 0.55, transparent: true, opacity: 0.55,
          depthWrite: false}));
        solid.add(body);   // see-through: the centre of mass and its path show inside
      }
      scene.add(solid);
    }

    // ---- camera
    // It looks along -spec.camera with spec.up up, and frames what is drawn: every body
    // over all frames (its bounding sphere), the fixed ends of rods (unless
    // spec.frame_rods is false: a rod that runs out of the view, the Foucault
    // pendulum's), the fixed lines (trails are the bodies' paths).  Target: the middle of
    // that in the view's plane; distance: the least that keeps every sphere inside the
    // frustum for the canvas's aspect (a margin of 8 %).  Refitted when the canvas's shape
    // changes and when a simulating page re-runs, until the user moves the camera.
    const FOV = 40;
    const camera = new THREE.PerspectiveCamera(FOV, W / H, 0.005 * ext, 200 * ext);
    camera.up.copy(V(spec.up));
    // the bodies' bounding radii, and the turned solid's bounding sphere in its own frame
    // (taken here, before any frame turns it)
    const rad = meshes.map((m) => {
      m.geometry.computeBoundingSphere();
      return m.geometry.boundingSphere.radius;
    });
    const solidSphere = new THREE.Sphere();
    if (solid) new THREE.Box3().setFromObject(solid).getBoundingSphere(solidSphere);
    const sc = solidSphere.center, sr = solidSphere.radius;
    // the bounding spheres of what is drawn over all frames: x, y, z, radius, ...
    function whatIsDrawn() {
      const drawn = [];
      const at = Array.from({length: nb}, () => new THREE.Vector3());
      const c = new THREE.Vector3();
      for (let k = 0; k < n; k++) {
        const q = place(k, at);
        for (let i = 0; i < nb; i++) drawn.push(at[i].x, at[i].y, at[i].z, rad[i]);
        if (solid) {
          c.copy(sc);
          if (q) c.applyQuaternion(q);
          drawn.push(c.x, c.y, c.z, sr);
        }
      }
      for (const e of spec.frame_rods === false ? [] : spec.rods.flatMap(([a, b]) => [a, b])) {
        if (typeof e !== "number") drawn.push(e[0], e[1], e[2], 0);
      }
      for (const ln of spec.lines) {
        const pts = mpUnpack(ln.pts);
        for (let j = 0; j < pts.length; j += 3) drawn.push(pts[j], pts[j + 1], pts[j + 2], 0);
      }
      return drawn;
    }
    const center = V(spec.center);
    const dir = V(spec.camera).normalize();
    function fitCamera() {
      const drawn = whatIsDrawn();
      const z = dir.clone(), x = new THREE.Vector3().crossVectors(camera.up, z).normalize();
      const y = new THREE.Vector3().crossVectors(z, x);
      const tv = 0.92 * Math.tan((FOV * Math.PI) / 360), th = tv * camera.aspect;
      let lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
      const p = new THREE.Vector3();
      for (let j = 0; j < drawn.length; j += 4) {
        p.set(drawn[j], drawn[j + 1], drawn[j + 2]);
        const r = drawn[j + 3], u = [p.dot(x), p.dot(y), p.dot(z)];
        for (let a = 0; a < 3; a++) {
          lo[a] = Math.min(lo[a], u[a] - r);
          hi[a] = Math.max(hi[a], u[a] + r);
        }
      }
      if (!(hi[0] >= lo[0])) { lo = [0, 0, 0]; hi = [0, 0, 0]; }
      const mid = lo.map((v, a) => 0.5 * (v + hi[a]));
      // the target: the middle across the view; distance along z from there
      center.set(0, 0, 0).addScaledVector(x, mid[0]).addScaledVector(y, mid[1])
        .addScaledVector(z, mid[2]);
      let D = 1e-3 * ext;
      for (let j = 0; j < drawn.length; j += 4) {
        p.set(drawn[j], drawn[j + 1], drawn[j + 2]).sub(center);
        const r = drawn[j + 3];
        D = Math.max(D, p.dot(z) + r + (Math.abs(p.dot(x)) + r) / th,
          p.dot(z) + r + (Math.abs(p.dot(y)) + r) / tv);
      }
      camera.position.copy(center).addScaledVector(z, D);
      camera.near = 2e-3 * D;
      camera.far = 100 * D;
      camera.updateProjectionMatrix();
      controls.target.copy(center);
      controls.update();
    }
    const controls = new OrbitControls(camera, renderer.domElement);
    controls.enableDamping = true;
    let moved = false;                                  // the user has moved the camera
    controls.addEventListener("start", () => { moved = true; });
    fitCamera();

    // ---- legend
    const seen = new Set();
    const entry = (c, text) => {
      if (!text || seen.has(text)) return;
      seen.add(text);
      legend.append(mpEl("div", {}, mpEl("span", {style: "display:inline-block;width:10px;"
        + `height:10px;background:${c};margin-right:4px`}), text));
    };
    spec.legend.forEach(([c, name]) => entry(c, name));   // as the drawing lists it
    spec.lines.forEach((l) => entry(l.color, l.label));

    // ---- frames
    let shown = -1, playing = true, head = 0, last = null, speed = spec.speed;
    let raf = 0, dead = false;
    // the rotations of the solids of kind "bodies" (frames x solids x 9, row-major)
    const Rs = sim && sim.R ? sim.R : spec.rots ? mpUnpack(spec.rots) : null;  // sim: its own
    const m4b = new THREE.Matrix4();
    const nrot = spec.bodies.filter((b) => b.rot !== null && b.rot !== undefined).length;
    function show(k) {
      const q = place(k, where);
      meshes.forEach((m, i) => {
        m.position.copy(where[i]);
        const b = spec.bodies[i];
        if (Rs && b.rot !== null && b.rot !== undefined) {   // a solid turned by its frame
          const r = Rs.subarray(9 * (k * nrot + b.rot), 9 * (k * nrot + b.rot) + 9);
          m4b.set(r[0], r[1], r[2], 0, r[3], r[4], r[5], 0, r[6], r[7], r[8], 0, 0, 0, 0, 1);
          m.quaternion.setFromRotationMatrix(m4b);
        } else if (b.shape === "cone" && !b.size) {     // an arrowhead along its axis
          tmp.copy(where[i]);
          const len = tmp.length();
          if (len > 0) m.quaternion.setFromUnitVectors(Y, tmp.divideScalar(len));
        }
      });
      if (solid && q) solid.quaternion.copy(q);
      rods.forEach(placeRod);
      plots.at(k);
      for (const tr of trails) {
        const first = Math.max(0, k - tr.window);
        tr.line.geometry.setDrawRange(first, k - first + 1);
      }
      clock.textContent = `t = ${T[k].toFixed(3)} s`;
      slider.set(k);
      slider.lastChild.textContent = String(k);
      shown = k;
      stale = true;
    }
    // drawn only when something changed (a frame, the camera, the trails): an idle page rests
    const fps = mpFps();
    let stale = true;
    function draw(now) {
      renderer.render(scene, camera);
      fps.tick(now);
      stale = false;
    }
    controls.addEventListener("change", () => { stale = true; });
    function tick(now) {
      if (dead) return;
      if (playing && last !== null) {
        head = (head + ((now - last) / 1000) * spec.fps * speed) % n;
        const k = Math.floor(head);
        if (k !== shown) show(k);
      }
      last = now;
      controls.update();
      if (stale) draw(now);
      if (!api.ready) api.ready = true;
      raf = requestAnimationFrame(tick);
    }

    // ---- controls
    const playBtn = mpButton("pause", () => (playing ? api.pause() : api.play()));
    const seek = (i) => { api.pause(); show(i); head = i; };
    const slider = mpSlider("frame", 0, n - 1, 0, 1, seek);
    const plots = mpPlotPanels(spec, T, MAXW, seek, sim);
    const speedRow = mpSlider("speed", 0.1, 10, speed, 0.1, (v) => { speed = v; });
    const trailBox = mpEl("input", {type: "checkbox", checked: "", "aria-label": "trails",
      onchange: () => {
        trails.forEach((tr) => { tr.line.visible = trailBox.checked; });
        stale = true;
      }});
    const bar = mpEl("div", {style: "display:flex;flex-wrap:wrap;gap:12px;align-items:center;"
      + "margin-top:6px"},
      playBtn, slider, speedRow,
      ...(trails.length ? [mpEl("label", {style: "font-size:13px"}, trailBox, " trails")] : []),
      ...(sim ? sim.controls(rerun) : []));
    // a simulating page's re-run (a slider, setParam): new trails, the shown frame again
    function rerun() {
      fillTrails();
      if (!moved) fitCamera();
      plots.draw(W);                              // the new series, their new ranges
      show(Math.max(shown, 0));
    }
    el.append(mpEl("div", {class: "mechpy-live mechpy-animate"}, title, stage, plots.box, bar));
    // the canvas fills the stage inside its border (clientWidth); a new width: a new size
    // and the camera's aspect, drawn at once
    function fitTo(w) {
      W = w; H = Math.round(aspect * W);
      stage.style.height = `${H + 2}px`;
      renderer.setSize(W, H);
      camera.aspect = W / H;
      camera.updateProjectionMatrix();
      if (!moved) fitCamera();
      plots.draw(W);
      if (shown >= 0) plots.at(shown);
      stale = true;
    }
    const follow = mpFollowWidth(stage, MAXW, fitTo);
    fitTo(follow.width);

    const api = {
      ready: false,
      kind: spec.kind,
      play() { playing = true; last = null; playBtn.textContent = "pause"; },
      pause() { playing = false; playBtn.textContent = "play"; },
      frame(i) {
        const k = Math.min(Math.max(Math.round(Number(i)) || 0, 0), n - 1);
        api.pause();
        head = k;
        show(k);
        draw(performance.now());
        return T[k];
      },
      frames: () => n,
      time: () => T[shown],
      shown: () => shown,
      bodies: () => spec.bodies.map((b) => b.name),
      // the places of the drawn bodies at the shown frame: x, y, z each, in the system's units
      positions: () => meshes.flatMap((m) => [m.position.x, m.position.y, m.position.z]),
      // each drawn solid's rotation, body to world, row-major (9 numbers a solid), read back
      // from the drawn objects: the turned solid of a top or rigid body, else every body
      rotations: () => (solid ? [solid] : meshes).flatMap((m) => {
        const e = new THREE.Matrix4().makeRotationFromQuaternion(m.quaternion).elements;
        return [e[0], e[4], e[8], e[1], e[5], e[9], e[2], e[6], e[10]];
      }),
      // the fixed lines drawn (nutation bounds, L, walls, ...): [{label, points: [x, y, z, ...]}]
      lines: () => spec.lines.map((l) => ({label: l.label, points: Array.from(mpUnpack(l.pts))})),
      // the series of plots=[...] as drawn: {t: [...], y: [...]} (name: the entry's label)
      plot(name) {
        const y = plots.series.get(String(name));
        if (!y) throw new Error(`no plot named ${name}; the plots: ${[...plots.series.keys()]}`);
        return {t: Array.from(T), y: Array.from(y)};
      },
      // frames drawn per second over the last second (a paused, untouched page draws none)
      fps: () => fps.value(),
    };
    if (sim) {
      // a page that simulates: a parameter changed as its slider does (the run's report),
      // the parameters' values, and the last run's {steps, rejected, evals, ms, status, t}
      api.setParam = (name, value) => {
        const r = sim.setParam(name, value);
        rerun();
        draw(performance.now());
        return r;
      };
      api.params = sim.params;
      api.simulation = sim.report;
    }
    const unregister = mpRegister(api);
    show(0);
    raf = requestAnimationFrame(tick);
    return () => {
      dead = true;
      follow.stop();
      cancelAnimationFrame(raf);
      controls.dispose();
      renderer.dispose();
      unregister();
    };
  },
};
