// mechpy.live.animate's page that simulates (spec.sim, made by mechpy/live/_simulate.py):
// the page integrates the system itself, in double precision, from its printed right-hand
// side, and computes the frames' places from the drawing's printed geometry.
//
// The integrator: Dormand and Prince's 5(4) pair (FSAL), the error of the 4th-order
// solution in the weighted RMS norm sqrt(mean((err_i / (atol + rtol max(|y0_i|, |y1_i|)))^2))
// with Hairer's step control (safety 0.9, the step 0.2 to 10 times the last) and initial step
// (dopri5's hinit), and Hairer's 4th-order dense output (contd5) for the states at the
// frames' times.  A mass-matrix system is solved by LU with partial pivoting at every
// evaluation: a Lagrangian's (sim.nc > 0: the printed field returns M(q) row-major, then
// F(q, q', t); y' = (q', M^-1 F)) or an mp.mechanics model's (sim.na > 0: A (na x na)
// row-major, then b, the linear system its C solves; y' = the first dim unknowns of A z = b).
// The printed geometry returns the places (3 a body), then for a mechanics model the
// rotations of its solids (9 each, row-major, body to world: sim.nrot of them), into R.
// A run takes at most sim.max_steps steps (frames x a cap): a runaway stops there, the
// frames after it hold the last state reached, and the page says so.

const MP_DOPRI = {
  c: [0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1, 1],
  a: [[], [1 / 5], [3 / 40, 9 / 40], [44 / 45, -56 / 15, 32 / 9],
    [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729],
    [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656],
    [35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84]],
  // the 5th-order weights minus the embedded 4th-order ones
  e: [71 / 57600, 0, -71 / 16695, 71 / 1920, -17253 / 339200, 22 / 525, -1 / 40],
  // Hairer's dense output (dopri5's d1 .. d7)
  d: [-12715105075 / 11282082432, 0, 87487479700 / 32700410799, -10690763975 / 1880347072,
    701980252875 / 199316789632, -1453857185 / 822651844, 69997945 / 29380423],
};

// x = A^-1 b for A (n x n, row-major, overwritten) by LU with partial pivoting; b overwritten
// by x.  A zero pivot gives non-finite values (the run then stops and says so).
function mpLuSolve(A, b, n) {
  for (let k = 0; k < n; k++) {
    let piv = k, big = Math.abs(A[k * n + k]);
    for (let i = k + 1; i < n; i++) {
      const v = Math.abs(A[i * n + k]);
      if (v > big) { big = v; piv = i; }
    }
    if (piv !== k) {
      for (let j = 0; j < n; j++) {
        const tmp = A[k * n + j]; A[k * n + j] = A[piv * n + j]; A[piv * n + j] = tmp;
      }
      const tb = b[k]; b[k] = b[piv]; b[piv] = tb;
    }
    const akk = A[k * n + k];
    for (let i = k + 1; i < n; i++) {
      const f = A[i * n + k] / akk;
      if (f === 0) continue;
      for (let j = k + 1; j < n; j++) A[i * n + j] -= f * A[k * n + j];
      b[i] -= f * b[k];
    }
  }
  for (let i = n - 1; i >= 0; i--) {
    let s = b[i];
    for (let j = i + 1; j < n; j++) s -= A[i * n + j] * b[j];
    b[i] = s / A[i * n + i];
  }
  return b;
}

// The simulation of spec (spec.sim): {P (frames x bodies x 3, rewritten by every run),
// R (frames x solids x 9, or null), S (a Float64Array of frames a series of plots=,
// rewritten by every run), run(), setParam(name, value), report(), controls(onRun),
// message (an element)}.
function mpSimulation(spec) {
  const sim = spec.sim, n = spec.n, nb = spec.nb, dim = sim.dim, nc = sim.nc;
  const na = sim.na || 0, nrot = sim.nrot || 0;
  const T = mpUnpack(spec.t);
  const p = sim.values.slice();
  const field = new Function("s", "t", "p", "mp", sim.field);
  const geometry = new Function("s", "t", "p", "mp", sim.geometry);
  // the series of plots= (spec.plots' order), at each frame's state: S[i][k]
  const series = sim.series ? new Function("s", "t", "p", "mp", sim.series) : null;
  const S = (spec.plots || []).map(() => new Float64Array(n));
  const rhs = na > 0
    ? (t, s) => {
      const out = field(s, t, p, MP_JS_MATH);
      return mpLuSolve(out.slice(0, na * na), out.slice(na * na), na).slice(0, dim);
    }
    : nc > 0
      ? (t, s) => {
        const out = field(s, t, p, MP_JS_MATH);
        const acc = mpLuSolve(out.slice(0, nc * nc), out.slice(nc * nc), nc);
        const f = new Array(dim);
        for (let i = 0; i < nc; i++) { f[i] = s[nc + i]; f[nc + i] = acc[i]; }
        return f;
      }
      : (t, s) => field(s, t, p, MP_JS_MATH);
  const P = new Float64Array(n * nb * 3), R = nrot ? new Float64Array(n * nrot * 9) : null;
  const message = mpEl("div", {style: "position:absolute;left:8px;bottom:6px;font-size:12px;"
    + "color:#b00;background:rgba(255,255,255,.85);padding:1px 4px;display:none"});
  let last = {steps: 0, rejected: 0, evals: 0, ms: 0, status: "not run", t: T[0]};

  const norm = (v, w) => {
    let s = 0;
    for (let i = 0; i < dim; i++) { const r = v[i] / w[i]; s += r * r; }
    return Math.sqrt(s / dim);
  };
  // the places at state y (frame k)
  function place(k, y) {
    const g = geometry(y, T[k], p, MP_JS_MATH);
    for (let i = 0; i < 3 * nb; i++) P[3 * nb * k + i] = g[i];
    for (let i = 0; i < 9 * nrot; i++) R[9 * nrot * k + i] = g[3 * nb + i];
    if (series) {
      const v = series(y, T[k], p, MP_JS_MATH);
      for (let i = 0; i < S.length; i++) S[i][k] = v[i];
    }
  }
  // Hairer's initial step (dopri5's hinit, order 5)
  function firstStep(t0, y0, f0, tend, rtol, atol) {
    const sc = y0.map((v) => atol + rtol * Math.abs(v));
    const d0 = norm(y0, sc), d1 = norm(f0, sc);
    let h0 = d0 < 1e-5 || d1 < 1e-5 ? 1e-6 : 0.01 * (d0 / d1);
    h0 = Math.min(h0, tend - t0);
    const f1 = rhs(t0 + h0, y0.map((v, i) => v + h0 * f0[i]));
    const d2 = norm(f1.map((v, i) => v - f0[i]), sc) / h0;
    const big = Math.max(d1, d2);
    const h1 = big <= 1e-15 ? Math.max(1e-6, h0 * 1e-3) : Math.pow(0.01 / big, 1 / 5);
    return Math.min(100 * h0, h1, tend - t0);
  }

  function run() {
    const start = performance.now();
    const {a, c, e, d} = MP_DOPRI, rtol = sim.rtol, atol = sim.atol;
    let t = T[0], y = sim.y0.slice(), tend = T[n - 1];
    let steps = 0, rejected = 0, evals = 0, status = "done", k = 1;
    const call = (tt, s) => { evals++; return rhs(tt, s); };
    place(0, y);
    let f = call(t, y);
    let h = firstStep(t, y, f, tend, rtol, atol);
    evals++;
    const K = new Array(7), ys = new Array(dim), err = new Array(dim), w = new Array(dim);
    let reject = false;
    while (k < n) {
      if (steps >= sim.max_steps) { status = "budget"; break; }
      if (!(h > 1e-14 * Math.max(1, Math.abs(t))) || !isFinite(h)) { status = "step"; break; }
      if (t + 1.01 * h >= tend) h = tend - t;
      K[0] = f;
      for (let st = 1; st < 7; st++) {
        for (let i = 0; i < dim; i++) {
          let s = 0;
          for (let j = 0; j < st; j++) if (a[st][j] !== 0) s += a[st][j] * K[j][i];
          ys[i] = y[i] + h * s;
        }
        K[st] = call(t + c[st] * h, ys.slice());
      }
      const y1 = ys.slice();                    // stage 7's argument: the 5th-order solution
      for (let i = 0; i < dim; i++) {
        let s = 0;
        for (let j = 0; j < 7; j++) s += e[j] * K[j][i];
        err[i] = h * s;
        w[i] = atol + rtol * Math.max(Math.abs(y[i]), Math.abs(y1[i]));
      }
      const en = norm(err, w);
      steps++;
      if (!isFinite(en)) { h *= 0.25; rejected++; reject = true; continue; }
      if (en > 1) {
        h *= Math.max(0.2, 0.9 * Math.pow(en, -0.2));
        rejected++;
        reject = true;
        continue;
      }
      // accepted: the frames in (t, t + h] from the dense output
      const tn = h === tend - t ? tend : t + h;
      while (k < n && T[k] <= tn) {
        const th = (T[k] - t) / h, th1 = 1 - th, yk = new Array(dim);
        for (let i = 0; i < dim; i++) {
          const dy = y1[i] - y[i], bs = h * K[0][i] - dy;
          let r5 = 0;
          for (let j = 0; j < 7; j++) r5 += d[j] * K[j][i];
          yk[i] = y[i] + th * (dy + th1 * (bs + th * (dy - h * K[6][i] - bs + th1 * h * r5)));
        }
        if (k === n - 1 && tn === tend) for (let i = 0; i < dim; i++) yk[i] = y1[i];
        place(k, yk);
        k++;
      }
      t = tn;
      y = y1;
      f = K[6];
      let fac = Math.min(10, Math.max(0.2, 0.9 * Math.pow(Math.max(en, 1e-300), -0.2)));
      if (reject) fac = Math.min(fac, 1);
      reject = false;
      h *= fac;
    }
    for (; k < n; k++) place(k, y);             // a stopped run: its last state
    last = {steps, rejected, evals, ms: performance.now() - start, status, t};
    const what = {budget: `the step budget (${sim.max_steps} steps) ran out`,
      step: "the step size fell to nothing (a singularity?)"}[status];
    message.textContent = what ? `simulation stopped at t = ${t.toPrecision(6)}: ${what}; `
      + "the later frames hold its last state" : "";
    message.style.display = what ? "block" : "none";
    return last;
  }

  const sliders = [];
  function setParam(name, value) {
    const j = sim.names.indexOf(name);
    if (j < 0) throw new Error(`${name} is not a parameter (${sim.names.join(", ")})`);
    if (sim.locked && sim.locked[name]) throw new Error(sim.locked[name]);
    p[j] = Number(value);
    sliders.forEach((sl) => { if (sl.name === name) sl.row.set(p[j]); });
    return run();
  }
  return {
    P, R, S, run, setParam, message,
    params: () => Object.fromEntries(sim.names.map((nm, j) => [nm, p[j]])),
    report: () => Object.assign({}, last),
    // one slider a params entry; onRun() after each re-run (the view redraws)
    controls(onRun) {
      return sim.sliders.map((q) => {
        const row = mpSlider(q.name, q.min, q.max, q.value, "any", (v) => {
          p[q.index] = v;
          run();
          onRun();
        });
        sliders.push({name: q.name, row});
        return row;
      });
    },
  };
}
