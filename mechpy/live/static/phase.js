// mechpy live phase portrait: particles advected through a system's field on the GPU.
//
// States live in RGBA32F textures (one texel a particle: up to 4 state components), two of
// them in turn: a fragment shader takes one RK4 step of dt for every particle at once, the
// field printed from the system's symbolic form (mp_field, mechpy.live._field.glsl) with the
// parameters as a uniform array, so a slider changes a uniform and never the program.  The
// points are drawn from the same texture into a trail texture that fades each frame, coloured
// by speed in the plane shown.  A 2D canvas on top draws the axes, the overlays (fixed points,
// nullclines, limit cycle) and the trajectories a click drops.

const MP_VS_FULL = `#version 300 es
void main() {
  vec2 v = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  gl_Position = vec4(v * 2.0 - 1.0, 0.0, 1.0);
}`;

// sin, cos, exp and log to about one float32 ulp (Cephes' sinf, cosf, expf, logf): GLSL ES
// leaves the built-ins' precision open, and software WebGL's sin is off by 2e-4.
const MP_GLSL_MATH = `
float mp_sincos(float x, bool wantCos) {
  float sgn = 1.0;
  if (x < 0.0) { x = -x; if (!wantCos) sgn = -1.0; }
  int j = int(x * 1.27323954473516);
  j += j & 1;
  float y = float(j);
  x = ((x - y * 0.78515625) - y * 2.4187564849853515625e-4) - y * 3.77489497744594108e-8;
  j &= 7;
  if (wantCos) { if (j > 3) { j -= 4; sgn = -sgn; } if (j > 1) sgn = -sgn; }
  else if (j > 3) { j -= 4; sgn = -sgn; }
  float z = x * x;
  float c = ((2.443315711809948e-5 * z - 1.388731625493765e-3) * z + 4.166664568298827e-2) * z * z
            - 0.5 * z + 1.0;
  float s = ((-1.9515295891e-4 * z + 8.3321608736e-3) * z - 1.6666654611e-1) * z * x + x;
  // octants 1 and 2 (after the shift) take the other polynomial
  bool swap = j == 1 || j == 2;
  return sgn * ((wantCos != swap) ? c : s);
}
float mp_sin(float x) { return mp_sincos(x, false); }
float mp_cos(float x) { return mp_sincos(x, true); }
float mp_tan(float x) { return mp_sin(x) / mp_cos(x); }
float mp_exp(float x) {
  if (x > 88.72283) return intBitsToFloat(0x7f800000);
  if (x < -103.97) return 0.0;
  float fx = floor(1.44269504088896341 * x + 0.5);
  x = x - fx * 0.693359375 - fx * -2.12194440e-4;
  float z = x * x;
  float y = (((((1.9875691500e-4 * x + 1.3981999507e-3) * x + 8.3334519073e-3) * x
             + 4.1665795894e-2) * x + 1.6666665459e-1) * x + 5.0000001201e-1) * z + x + 1.0;
  int n = int(fx);
  // 2^n in two halves (n may reach -150, below the smallest normal exponent)
  int h = n / 2;
  return y * intBitsToFloat((h + 127) << 23) * intBitsToFloat((n - h + 127) << 23);
}
float mp_log(float x) {
  if (!(x > 0.0)) return x == 0.0 ? intBitsToFloat(int(0xff800000u)) : intBitsToFloat(0x7fc00000);
  if (isinf(x)) return x;
  int b = floatBitsToInt(x);
  int e = ((b >> 23) & 255) - 126;
  float m = intBitsToFloat((b & 0x7fffff) | 0x3f000000);
  if (m < 0.707106781186547524) { e -= 1; m = m + m - 1.0; } else { m = m - 1.0; }
  float z = m * m;
  float y = ((((((((7.0376836292e-2 * m - 1.1514610310e-1) * m + 1.1676998740e-1) * m
              - 1.2420140846e-1) * m + 1.4249322787e-1) * m - 1.6668057665e-1) * m
              + 2.0000714765e-1) * m - 2.4999993993e-1) * m + 3.3333331174e-1) * m * z;
  float fe = float(e);
  y += -2.12194440e-4 * fe;
  y += -0.5 * z;
  return m + y + 0.693359375 * fe;
}
// b^n for an integer n by repeated squaring: a negative base keeps its sign by parity, as
// C's pow (GLSL's pow is undefined for b < 0); about log2|n| float32 roundings.
float mp_powi(float b, int n) {
  uint m = uint(n < 0 ? -n : n);
  float r = 1.0;
  while (m != 0u) {
    if ((m & 1u) != 0u) r *= b;
    m >>= 1;
    if (m != 0u) b *= b;
  }
  return n < 0 ? 1.0 / r : r;
}
// C's pow for a real exponent: 1 at x = 0 or b = 1; an integral x by mp_powi (beyond 2^24
// every float is an even integer); a negative base and a non-integral x NaN.
float mp_pow(float b, float x) {
  const float inf = intBitsToFloat(0x7f800000), nan = intBitsToFloat(0x7fc00000);
  if (x == 0.0 || b == 1.0) return 1.0;
  if (isnan(b) || isnan(x)) return nan;
  if (isinf(x)) {
    float a = abs(b);
    return a == 1.0 ? 1.0 : ((a > 1.0) == (x > 0.0) ? inf : 0.0);
  }
  bool integral = floor(x) == x;
  if (integral && abs(x) <= 16777216.0) return mp_powi(b, int(x));
  if (b < 0.0) {
    if (isinf(b) && !integral) return x > 0.0 ? inf : 0.0;
    return integral ? mp_exp(x * mp_log(-b)) : nan;
  }
  return mp_exp(x * mp_log(b));
}
// log(1 + u) without the rounding of 1 + u: below |u| = 0.3 by the series of
// 2 atanh(u / (2 + u)) (|u / (2 + u)| < 0.18: seven terms), else mp_log(1 + u).  (Not
// Goldberg's mp_log(w) u / (w - 1): a shader compiler may fold (1 + u) - 1 to u.)
float mp_log1p(float u) {
  if (!(abs(u) < 0.3)) return mp_log(1.0 + u);
  float s = u / (2.0 + u), z = s * s;
  return 2.0 * s * (1.0 + z * (1.0 / 3.0 + z * (1.0 / 5.0 + z * (1.0 / 7.0 + z * (1.0 / 9.0
         + z * (1.0 / 11.0 + z * (1.0 / 13.0)))))));
}
// The hyperbolic functions and their inverses from mp_exp and mp_log (sinh by its Taylor
// series below 1, tanh through it below 0.625, the inverses through mp_log1p): a few float32
// ulps, where software WebGL's built-ins lose the small arguments.
float mp_sinh(float x) {
  float a = abs(x), r;
  if (a < 1.0) {
    float z = a * a;
    r = a * (1.0 + z * (1.0 / 6.0 + z * (1.0 / 120.0 + z * (1.0 / 5040.0 + z * (1.0 / 362880.0
        + z * (1.0 / 39916800.0))))));
  } else if (a > 88.0) {
    float e = mp_exp(0.5 * a);
    r = (0.5 * e) * e;
  } else {
    float e = mp_exp(a);
    r = 0.5 * (e - 1.0 / e);
  }
  return x < 0.0 ? -r : r;
}
float mp_cosh(float x) {
  float a = abs(x);
  if (a > 88.0) { float e = mp_exp(0.5 * a); return (0.5 * e) * e; }
  float e = mp_exp(a);
  return 0.5 * (e + 1.0 / e);
}
float mp_tanh(float x) {
  float a = abs(x), r;
  if (a < 0.625) { float s = mp_sinh(a); r = s / sqrt(1.0 + s * s); }
  else if (a > 9.1) r = 1.0;
  else r = 1.0 - 2.0 / (mp_exp(2.0 * a) + 1.0);
  return x < 0.0 ? -r : r;
}
float mp_asinh(float x) {
  float a = abs(x), r;
  if (a > 4096.0) r = mp_log(a) + 0.693147180559945309;
  else r = mp_log1p(a + a * a / (1.0 + sqrt(1.0 + a * a)));
  return x < 0.0 ? -r : r;
}
float mp_acosh(float x) {
  if (!(x >= 1.0)) return intBitsToFloat(0x7fc00000);
  if (x > 4096.0) return mp_log(x) + 0.693147180559945309;
  float z = x - 1.0;
  return mp_log1p(z + sqrt(z * (x + 1.0)));
}
float mp_atanh(float x) {
  float a = abs(x);
  if (!(a < 1.0)) return a == 1.0 ? x * intBitsToFloat(0x7f800000) : intBitsToFloat(0x7fc00000);
  float r = 0.5 * mp_log1p(2.0 * a / (1.0 - a));
  return x < 0.0 ? -r : r;
}
// exp(-a^2) for 0 <= a < 16 with a^2 split (ah: 12 significant bits, so ah^2 is exact):
// the rounding of a^2 would cost a^2 float32 ulps.
float mp_expmsq(float a) {
  float ah = floor(a * 256.0) / 256.0, al = a - ah;
  return mp_exp(-ah * ah) * mp_exp(-al * (ah + a));
}
// erf and erfc in float32: erf below 2 by its series exp(-a^2) sum (2a^2)^n a / (2n+1)!!
// (positive terms), erfc by 1 - erf below 0.5, exp(-a^2) times a degree-10 fit of
// exp(a^2) erfc(a) on [0.5, 2] (1.2e-7 relative in float32), its continued fraction beyond
// (24 terms: float32's precision from a = 2 on).
float mp_erf_series(float a) {
  float term = a, sum = a, z = 2.0 * a * a;
  for (int n = 1; n < 60; n++) {
    term *= z / float(2 * n + 1);
    sum += term;
    if (term < 1.0e-8 * sum) break;
  }
  return 1.1283791670955126 * mp_expmsq(a) * sum;
}
float mp_erfc_pos(float a) {
  if (a < 0.5) return 1.0 - mp_erf_series(a);
  if (a < 2.0) {
    float u = (2.0 * a - 2.5) / 1.5;
    float q = (((((((((3.608895106e-06 * u - 1.445295319e-05) * u + 4.679475406e-05) * u
               - 1.746835557e-04) * u + 6.327226311e-04) * u - 2.156129037e-03) * u
               + 6.964451501e-03) * u - 2.118565134e-02) * u + 6.007251602e-02) * u
               - 1.566164162e-01) * u + 3.678229164e-01;
    return mp_expmsq(a) * q;
  }
  if (a > 10.1) return 0.0;
  float f = a;
  for (int n = 24; n > 0; n--) f = a + 0.5 * float(n) / f;
  return mp_expmsq(a) / (1.7724538509055160 * f);
}
float mp_erf(float x) {
  float a = abs(x);
  float r = a < 2.0 ? mp_erf_series(a) : 1.0 - mp_erfc_pos(a);
  return x < 0.0 ? -r : r;
}
float mp_erfc(float x) { return x < 0.0 ? 2.0 - mp_erfc_pos(-x) : mp_erfc_pos(x); }
`;

function mpFieldGlsl(spec) {
  const np = Math.max(1, spec.params.length);
  return `${MP_GLSL_MATH}
uniform float p[${np}];
vec4 mp_field(vec4 s, float t) {
  vec4 f = vec4(0.0);
${spec.glsl}
  return f;
}`;
}

// One RK4 step of dt for every particle; in play, a particle that left the region kept, whose
// state is not finite, or that the drop draw picks, starts again at a random seed state.
function mpUpdateFs(spec) {
  const [ax, ay] = spec.axes;
  return `#version 300 es
precision highp float;
precision highp int;
uniform highp sampler2D u_state;
uniform float u_t, u_dt, u_drop;
uniform int u_respawn, u_w;
uniform uint u_frame;
uniform vec4 u_lo, u_hi, u_keep;
out vec4 o;
${mpFieldGlsl(spec)}
uint mp_hash(uint x) {
  x ^= x >> 16; x *= 0x7feb352du; x ^= x >> 15; x *= 0x846ca68bu; x ^= x >> 16; return x;
}
float mp_rnd(uint id, uint k) {
  return float(mp_hash(id * 5u + k + mp_hash(u_frame))) / 4294967296.0;
}
void main() {
  ivec2 ij = ivec2(gl_FragCoord.xy);
  vec4 s = texelFetch(u_state, ij, 0);
  float h = u_dt, t = u_t;
  vec4 k1 = mp_field(s, t);
  vec4 k2 = mp_field(s + (0.5 * h) * k1, t + 0.5 * h);
  vec4 k3 = mp_field(s + (0.5 * h) * k2, t + 0.5 * h);
  vec4 k4 = mp_field(s + h * k3, t + h);
  vec4 n = s + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
  if (u_respawn == 1) {
    uint id = uint(ij.y * u_w + ij.x);
    float x = n[${ax}], y = n[${ay}];
    bool lost = any(isnan(n)) || any(isinf(n)) || x < u_keep.x || x > u_keep.y ||
                y < u_keep.z || y > u_keep.w;
    if (lost || mp_rnd(id, 0u) < u_drop) {
      vec4 r = vec4(mp_rnd(id, 1u), mp_rnd(id, 2u), mp_rnd(id, 3u), mp_rnd(id, 4u));
      n = u_lo + r * (u_hi - u_lo);
    }
  }
  o = n;
}`;
}

function mpPointsVs(spec) {
  const [ax, ay] = spec.axes;
  return `#version 300 es
precision highp float;
precision highp int;
uniform highp sampler2D u_state;
uniform int u_w;
uniform float u_t, u_speed, u_size;
uniform vec4 u_view;
out float v_speed;
${mpFieldGlsl(spec)}
void main() {
  ivec2 ij = ivec2(gl_VertexID % u_w, gl_VertexID / u_w);
  vec4 s = texelFetch(u_state, ij, 0);
  vec4 f = mp_field(s, u_t);
  float sp = length(vec2(f[${ax}], f[${ay}]));
  v_speed = sp / (sp + u_speed);
  vec2 q = vec2(s[${ax}], s[${ay}]);
  vec2 c = (q - u_view.xz) / (u_view.yw - u_view.xz) * 2.0 - 1.0;
  gl_Position = vec4(c, 0.0, 1.0);
  gl_PointSize = u_size;
}`;
}

const MP_POINTS_FS = `#version 300 es
precision highp float;
in float v_speed;
out vec4 o;
vec3 mp_viridis(float x) {
  const vec3 c0 = vec3(0.2777, 0.0054, 0.3340), c1 = vec3(0.1051, 1.4046, 1.3846);
  const vec3 c2 = vec3(-0.3309, 0.2148, 0.0951), c3 = vec3(-4.6342, -5.7991, -19.3324);
  const vec3 c4 = vec3(6.2283, 14.1799, 56.6906), c5 = vec3(4.7764, -13.7451, -65.3530);
  const vec3 c6 = vec3(-5.4355, 4.6459, 26.3124);
  return c0 + x * (c1 + x * (c2 + x * (c3 + x * (c4 + x * (c5 + x * c6)))));
}
void main() { o = vec4(mp_viridis(clamp(0.15 + 0.85 * v_speed, 0.0, 1.0)), 1.0); }`;

const MP_FADE_FS = `#version 300 es
precision highp float;
uniform sampler2D u_prev;
uniform float u_fade;
out vec4 o;
const vec3 bg = vec3(0.043, 0.051, 0.09);
void main() {
  vec4 c = texelFetch(u_prev, ivec2(gl_FragCoord.xy), 0);
  // the extra 1.5/255 lets an 8-bit trail reach the background (rounding would hold it)
  o = vec4(bg + max((c.rgb - bg) * u_fade - 1.5 / 255.0, 0.0), 1.0);
}`;

function mpProgram(gl, vs, fs) {
  const sh = (type, src) => {
    const s = gl.createShader(type);
    gl.shaderSource(s, src);
    gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS))
      throw new Error("shader: " + gl.getShaderInfoLog(s) + "\n" + src);
    return s;
  };
  const p = gl.createProgram();
  gl.attachShader(p, sh(gl.VERTEX_SHADER, vs));
  gl.attachShader(p, sh(gl.FRAGMENT_SHADER, fs));
  gl.linkProgram(p);
  if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error("link: " + gl.getProgramInfoLog(p));
  const u = {};
  const n = gl.getProgramParameter(p, gl.ACTIVE_UNIFORMS);
  for (let i = 0; i < n; i++) {
    const name = gl.getActiveUniform(p, i).name.replace(/\[0\]$/, "");
    u[name] = gl.getUniformLocation(p, name);
  }
  return {p, u};
}

function mpTexture(gl, w, h, float, data) {
  const t = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D, t);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
  if (float) gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, w, h, 0, gl.RGBA, gl.FLOAT, data || null);
  else gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA8, w, h, 0, gl.RGBA, gl.UNSIGNED_BYTE, null);
  const fb = gl.createFramebuffer();
  gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
  gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, t, 0);
  if (gl.checkFramebufferStatus(gl.FRAMEBUFFER) !== gl.FRAMEBUFFER_COMPLETE)
    throw new Error("this browser cannot render to a " + (float ? "float " : "") + "texture");
  gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  return {t, fb};
}

// The page's own RK4 in double precision (a dropped trajectory without a kernel).
function mpRk4Path(f, y0, t0, dt, nsteps, p, keep, ax, ay) {
  const n = y0.length, out = [[y0[ax], y0[ay]]];
  let y = y0.slice(), t = t0;
  const add = (a, b, c) => a.map((v, i) => v + c * b[i]);
  for (let k = 0; k < nsteps; k++) {
    const k1 = f(y, t, p), k2 = f(add(y, k1, dt / 2), t + dt / 2, p);
    const k3 = f(add(y, k2, dt / 2), t + dt / 2, p), k4 = f(add(y, k3, dt), t + dt, p);
    for (let i = 0; i < n; i++) y[i] += (dt / 6) * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
    t += dt;
    if (!y.every(Number.isFinite)) break;
    out.push([y[ax], y[ay]]);
    if (y[ax] < keep[0] || y[ax] > keep[1] || y[ay] < keep[2] || y[ay] > keep[3]) break;
  }
  return out;
}

function render({model, el}) {
  const spec = model.get("spec");
  const offline = !!model.get("_offline");
  const dim = spec.dim, [ax, ay] = spec.axes, N = spec.particles;
  const W = Math.ceil(Math.sqrt(N)), H = Math.ceil(N / W);
  // spec.width: the most the view takes (it follows its container: mpFollowWidth)
  let width = spec.width;
  const height = spec.height;
  const pvals = new Float32Array(Math.max(1, spec.params.length));
  spec.params.forEach((q, j) => { pvals[j] = q.value; });
  // the printed field in double precision: (state, t, parameters) -> dy/dt, with the
  // parameters as doubles (pvals, the shader's uniform, holds them in float32)
  const jsBody = new Function("s", "t", "p", "mp", spec.js);
  const jsField = (s, tt, p) => jsBody(s, tt, p, MP_JS_MATH);
  const pv64 = spec.params.map((q) => q.value);
  let view = [spec.xlim[0], spec.xlim[1], spec.ylim[0], spec.ylim[1]];
  let t = spec.t0, frameNo = 0, playing = !!spec.play, disposed = false;
  const fps = mpFps();

  // the page
  const root = mpEl("div", {class: "mechpy-live mechpy-phase", style: "font-family:system-ui,sans-serif;color:#222"});
  const stage = mpEl("div", {style: `position:relative;width:100%;max-width:${spec.width}px;height:${height}px`});
  const canvas = mpEl("canvas", {width: String(width), height: String(height),
    style: "position:absolute;left:0;top:0;width:100%;height:100%"});
  const over = mpEl("canvas", {width: String(width), height: String(height),
    style: "position:absolute;left:0;top:0;width:100%;height:100%;cursor:crosshair"});
  stage.append(canvas, over);
  const status = mpEl("span", {style: "font-size:12px;color:#555;margin-left:8px"});
  const playBtn = mpButton(playing ? "pause" : "play", () => (playing ? api.pause() : api.play()));
  const controls = mpEl("div", {style: "margin:6px 0;display:flex;flex-wrap:wrap;gap:4px 16px;align-items:center"},
    mpEl("span", {}, playBtn, mpButton("reset view", () => setView(spec.xlim.concat(spec.ylim))),
      mpButton("clear paths", () => { paths.length = 0; drawOverlay(); })), status);
  const sliders = {};
  for (const q of spec.params) {
    if (q.min === null || q.max === null) continue;
    const step = (q.max - q.min) / 500;
    sliders[q.name] = mpSlider(q.name, q.min, q.max, q.value, step, (v) => api.setParam(q.name, v));
    controls.append(sliders[q.name]);
  }
  root.append(stage, controls);
  el.append(root);
  // the canvases' pixels match the stage's width (laid out now that it is in the page)
  const follow = mpFollowWidth(stage, spec.width, (w) => resize(w));
  width = follow.width;
  canvas.width = over.width = width;

  const gl = canvas.getContext("webgl2", {antialias: false, preserveDrawingBuffer: false});
  if (!gl || !gl.getExtension("EXT_color_buffer_float")) {
    follow.stop();
    root.prepend(mpEl("p", {style: "color:#a00"}, "This browser has no WebGL2 with float render targets."));
    return;
  }
  const upd = mpProgram(gl, MP_VS_FULL, mpUpdateFs(spec));
  const pts = mpProgram(gl, mpPointsVs(spec), MP_POINTS_FS);
  const fade = mpProgram(gl, MP_VS_FULL, MP_FADE_FS);
  const vao = gl.createVertexArray();
  gl.bindVertexArray(vao);

  // seeds: the shown axes uniform over the view, the other components over their ranges
  const rnd = mpRandom(spec.seed);
  const seedBox = () => {
    const lo = [0, 0, 0, 0], hi = [0, 0, 0, 0];
    for (let i = 0; i < dim; i++) { lo[i] = spec.hidden[i][0]; hi[i] = spec.hidden[i][1]; }
    lo[ax] = view[0]; hi[ax] = view[1]; lo[ay] = view[2]; hi[ay] = view[3];
    return [lo, hi];
  };
  const seeds = new Float32Array(W * H * 4);
  {
    const [lo, hi] = seedBox();
    for (let k = 0; k < W * H; k++)
      for (let i = 0; i < 4; i++) seeds[4 * k + i] = i < dim ? lo[i] + rnd() * (hi[i] - lo[i]) : 0;
  }
  let cur = mpTexture(gl, W, H, true, seeds), nxt = mpTexture(gl, W, H, true, null);
  let trailA = mpTexture(gl, width, height, false), trailB = mpTexture(gl, width, height, false);

  // colour scale: the median speed in the plane over the seeds
  let speedScale = 1;
  const setSpeedScale = () => {
    const sp = [];
    for (let k = 0; k < Math.min(N, 2000); k++) {
      const s = Array.from(seeds.subarray(4 * k, 4 * k + dim));
      const f = jsField(s, t, pv64);
      const v = Math.hypot(f[ax], f[ay]);
      if (Number.isFinite(v)) sp.push(v);
    }
    sp.sort((a, b) => a - b);
    speedScale = sp.length ? Math.max(sp[Math.floor(sp.length / 2)], 1e-12) : 1;
  };
  setSpeedScale();

  function advance(respawn) {
    gl.bindFramebuffer(gl.FRAMEBUFFER, nxt.fb);
    gl.viewport(0, 0, W, H);
    gl.useProgram(upd.p);
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, cur.t);
    gl.uniform1i(upd.u.u_state, 0);
    gl.uniform1f(upd.u.u_t, t);
    gl.uniform1f(upd.u.u_dt, spec.dt);
    gl.uniform1f(upd.u.u_drop, spec.drop);
    gl.uniform1i(upd.u.u_respawn, respawn ? 1 : 0);
    gl.uniform1i(upd.u.u_w, W);
    gl.uniform1ui(upd.u.u_frame, frameNo >>> 0);
    const [lo, hi] = seedBox();
    gl.uniform4fv(upd.u.u_lo, lo);
    gl.uniform4fv(upd.u.u_hi, hi);
    const mx = 0.25 * (view[1] - view[0]), my = 0.25 * (view[3] - view[2]);
    gl.uniform4f(upd.u.u_keep, view[0] - mx, view[1] + mx, view[2] - my, view[3] + my);
    gl.uniform1fv(upd.u.p, pvals);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    [cur, nxt] = [nxt, cur];
    t += spec.dt;
    frameNo++;
  }

  function draw() {
    // fade the trails, draw the points over them, show
    gl.viewport(0, 0, width, height);
    gl.bindFramebuffer(gl.FRAMEBUFFER, trailB.fb);
    gl.useProgram(fade.p);
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, trailA.t);
    gl.uniform1i(fade.u.u_prev, 0);
    gl.uniform1f(fade.u.u_fade, spec.fade);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    gl.useProgram(pts.p);
    gl.bindTexture(gl.TEXTURE_2D, cur.t);
    gl.uniform1i(pts.u.u_state, 0);
    gl.uniform1i(pts.u.u_w, W);
    gl.uniform1f(pts.u.u_t, t);
    gl.uniform1f(pts.u.u_speed, speedScale);
    gl.uniform1f(pts.u.u_size, spec.point_size);
    gl.uniform4f(pts.u.u_view, view[0], view[1], view[2], view[3]);
    gl.uniform1fv(pts.u.p, pvals);
    gl.drawArrays(gl.POINTS, 0, N);
    // show: a copy, no shader
    gl.bindFramebuffer(gl.READ_FRAMEBUFFER, trailB.fb);
    gl.bindFramebuffer(gl.DRAW_FRAMEBUFFER, null);
    gl.blitFramebuffer(0, 0, width, height, 0, 0, width, height, gl.COLOR_BUFFER_BIT, gl.NEAREST);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    [trailA, trailB] = [trailB, trailA];
    fps.tick(performance.now());
  }

  function clearTrails() {
    for (const tr of [trailA, trailB]) {
      gl.bindFramebuffer(gl.FRAMEBUFFER, tr.fb);
      gl.clearColor(0.043, 0.051, 0.09, 1);
      gl.clear(gl.COLOR_BUFFER_BIT);
    }
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  }
  clearTrails();

  // a new width: the trails start afresh at the new size, the overlays are redrawn
  function resize(w) {
    width = w;
    canvas.width = over.width = width;
    for (const tr of [trailA, trailB]) { gl.deleteFramebuffer(tr.fb); gl.deleteTexture(tr.t); }
    trailA = mpTexture(gl, width, height, false);
    trailB = mpTexture(gl, width, height, false);
    clearTrails();
    drawOverlay();
    draw();
  }

  // overlays: the set for the current parameters (the kernel's answer, or the nearest
  // precomputed one in a saved page)
  let shown = spec.overlays ? spec.overlays.sets[spec.overlays.initial] : null;
  const paths = [];
  const toPx = (x, y) => [(x - view[0]) / (view[1] - view[0]) * width,
                          (1 - (y - view[2]) / (view[3] - view[2])) * height];
  const ctx = over.getContext("2d");
  // mechpy.phase's kinds: a saddle orange, a centre white, others green when stable
  // (filled) and red when not (hollow)
  const kindStyle = (kind, stable) => kind === "saddle" ? ["#ff7f0e", false]
    : kind === "centre" ? ["#ffffff", false] : stable ? ["#2ca02c", true] : ["#d62728", false];
  function drawOverlay() {
    ctx.clearRect(0, 0, width, height);
    ctx.lineWidth = 1;
    ctx.strokeStyle = "rgba(255,255,255,0.35)";
    ctx.fillStyle = "rgba(255,255,255,0.75)";
    ctx.font = "11px system-ui,sans-serif";
    // ticks
    const ticks = (a, b) => {
      const span = b - a, m = Math.pow(10, Math.floor(Math.log10(span / 5)));
      const st = [1, 2, 5, 10].map((k) => k * m).find((s) => span / s <= 8);
      const out = [];
      for (let v = Math.ceil(a / st) * st; v <= b; v += st) out.push(Math.abs(v) < st * 1e-9 ? 0 : v);
      return out;
    };
    for (const v of ticks(view[0], view[1])) {
      const [px] = toPx(v, view[2]);
      ctx.beginPath(); ctx.moveTo(px, height); ctx.lineTo(px, height - 6); ctx.stroke();
      ctx.fillText(String(+v.toPrecision(6)), px + 2, height - 8);
    }
    for (const v of ticks(view[2], view[3])) {
      const [, py] = toPx(view[0], v);
      ctx.beginPath(); ctx.moveTo(0, py); ctx.lineTo(6, py); ctx.stroke();
      ctx.fillText(String(+v.toPrecision(6)), 8, py - 2);
    }
    ctx.fillText(`${spec.names[ax]} →`, width - 70, height - 22);
    ctx.fillText(`↑ ${spec.names[ay]}`, 8, 14);
    const line = (pts2, color, w, dash) => {
      if (!pts2 || pts2.length < 2) return;
      ctx.strokeStyle = color; ctx.lineWidth = w; ctx.setLineDash(dash || []);
      ctx.beginPath();
      pts2.forEach(([x, y], i) => { const [px, py] = toPx(x, y); if (i) ctx.lineTo(px, py); else ctx.moveTo(px, py); });
      ctx.stroke(); ctx.setLineDash([]);
    };
    if (shown) {
      for (const c of shown.nullclines || []) line(c.points, c.which === 0 ? "#9ecae1" : "#fdae6b", 1.2, [5, 4]);
      line(shown.limit_cycle, "#ffffff", 2.5);
      for (const [x, y, kind, stable] of shown.fixed_points || []) {
        const [px, py] = toPx(x, y), [col, filled] = kindStyle(kind, stable);
        ctx.beginPath(); ctx.arc(px, py, 5, 0, 2 * Math.PI);
        ctx.lineWidth = 2; ctx.strokeStyle = col; ctx.stroke();
        if (filled) { ctx.fillStyle = col; ctx.fill(); }
      }
    }
    for (const pth of paths) line(pth, "#ff4fd8", 1.8);
  }

  function nearestSet(name) {
    if (!spec.overlays) return null;
    let best = null, bd = Infinity;
    for (const s of spec.overlays.sets) {
      let d = 0;
      spec.params.forEach((q, j) => {
        const span = (q.max !== null && q.max > q.min) ? q.max - q.min : 1;
        d += ((s.values[q.name] - pv64[j]) / span) ** 2;
      });
      if (d < bd) { bd = d; best = s; }
    }
    return best;
  }

  // requests to the kernel (none in a saved page): id -> resolve
  let reqId = 0;
  const pending = {};
  model.on("msg:custom", (msg) => {
    const f = pending[msg.id];
    if (f) { delete pending[msg.id]; f(msg); }
  });
  const ask = (content, timeoutMs) => new Promise((resolve) => {
    if (offline) return resolve(null);
    const id = ++reqId;
    pending[id] = resolve;
    model.send(Object.assign({id}, content));
    setTimeout(() => { if (pending[id]) { delete pending[id]; resolve(null); } }, timeoutMs);
  });
  const paramDict = () => Object.fromEntries(spec.params.map((q, j) => [q.name, pv64[j]]));

  let overlayTimer = null;
  function refreshOverlays() {
    if (!spec.overlays) return;
    shown = nearestSet();
    drawOverlay();
    clearTimeout(overlayTimer);
    if (offline) return;
    overlayTimer = setTimeout(async () => {
      const reply = await ask({type: "overlays", params: paramDict()}, 20000);
      if (reply && reply.type === "overlays") { shown = reply.data; drawOverlay(); }
    }, 150);
  }

  async function dropPath(x, y) {
    const y0 = new Array(dim).fill(0);
    for (let i = 0; i < dim; i++) y0[i] = 0.5 * (spec.hidden[i][0] + spec.hidden[i][1]);
    y0[ax] = x; y0[ay] = y;
    const reply = await ask({type: "trajectory", y0, t0: t, params: paramDict()}, 20000);
    let path;
    if (reply && reply.type === "trajectory") path = reply.points;
    else {
      const mx = view[1] - view[0], my = view[3] - view[2];
      path = mpRk4Path(jsField, y0, t, spec.dt, spec.path_steps, pv64.slice(),
        [view[0] - mx, view[1] + mx, view[2] - my, view[3] + my], ax, ay);
    }
    paths.push(path);
    drawOverlay();
  }

  function setView(v) {
    view = v.slice();
    clearTrails();
    drawOverlay();
    draw();
  }

  // pan (drag), zoom (wheel), click: a trajectory
  let drag = null;
  over.addEventListener("mousedown", (e) => { drag = {x: e.offsetX, y: e.offsetY, v: view.slice(), moved: false}; });
  over.addEventListener("mousemove", (e) => {
    if (!drag) return;
    const dx = e.offsetX - drag.x, dy = e.offsetY - drag.y;
    if (Math.abs(dx) + Math.abs(dy) > 3) drag.moved = true;
    if (!drag.moved) return;
    const sx = (drag.v[1] - drag.v[0]) / width, sy = (drag.v[3] - drag.v[2]) / height;
    setView([drag.v[0] - dx * sx, drag.v[1] - dx * sx, drag.v[2] + dy * sy, drag.v[3] + dy * sy]);
  });
  over.addEventListener("mouseup", (e) => {
    if (drag && !drag.moved) {
      const x = view[0] + (e.offsetX / width) * (view[1] - view[0]);
      const y = view[2] + (1 - e.offsetY / height) * (view[3] - view[2]);
      dropPath(x, y);
    }
    drag = null;
  });
  over.addEventListener("mouseleave", () => { drag = null; });
  over.addEventListener("wheel", (e) => {
    e.preventDefault();
    const k = Math.exp(0.0015 * e.deltaY);
    const x = view[0] + (e.offsetX / width) * (view[1] - view[0]);
    const y = view[2] + (1 - e.offsetY / height) * (view[3] - view[2]);
    setView([x + (view[0] - x) * k, x + (view[1] - x) * k, y + (view[2] - y) * k, y + (view[3] - y) * k]);
  }, {passive: false});

  function loop() {
    if (disposed) return;
    if (playing) {
      for (let k = 0; k < spec.steps_per_frame; k++) advance(true);
      draw();
      status.textContent = `t = ${t.toFixed(2)}   ${N} particles   ${fps.value().toFixed(0)} fps`;
    }
    requestAnimationFrame(loop);
  }

  const api = {
    kind: "phase_portrait",
    ready: false,
    pause() { playing = false; playBtn.textContent = "play"; },
    play() { playing = true; playBtn.textContent = "pause"; },
    // n RK4 steps of dt for every particle, no respawning, then one frame drawn
    step(n) {
      for (let k = 0; k < (n === undefined ? 1 : n); k++) advance(false);
      draw();
      return t;
    },
    particles() {
      const buf = new Float32Array(W * H * 4);
      gl.bindFramebuffer(gl.FRAMEBUFFER, cur.fb);
      gl.readPixels(0, 0, W, H, gl.RGBA, gl.FLOAT, buf);
      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
      const out = new Float32Array(N * dim);
      for (let k = 0; k < N; k++) for (let i = 0; i < dim; i++) out[k * dim + i] = buf[4 * k + i];
      return out;
    },
    seeds() {
      const out = new Float32Array(N * dim);
      for (let k = 0; k < N; k++) for (let i = 0; i < dim; i++) out[k * dim + i] = seeds[4 * k + i];
      return out;
    },
    setParam(name, value) {
      const j = spec.params.findIndex((q) => q.name === name);
      if (j < 0) throw new Error(`no parameter ${name}; the parameters are ${spec.params.map((q) => q.name).join(", ")}`);
      pvals[j] = value;
      pv64[j] = value;
      if (sliders[name]) sliders[name].set(value);
      refreshOverlays();
      if (!playing) draw();
    },
    params() { return paramDict(); },
    // dy/dt at a state from the page's printed JavaScript (double precision; t: now)
    field(s, tt) { return jsField(Array.from(s), tt === undefined ? t : tt, pv64); },
    overlays() { return shown ? JSON.parse(JSON.stringify(shown)) : {fixed_points: [], nullclines: [], limit_cycle: []}; },
    paths() { return JSON.parse(JSON.stringify(paths)); },
    dropPath(x, y) { return dropPath(x, y); },
    fps() { return fps.value(); },
    time() { return t; },
    view() { return view.slice(); },
    setView(v) { setView(v); },
  };
  const unregister = mpRegister(api);
  drawOverlay();
  draw();
  api.ready = true;
  requestAnimationFrame(loop);
  return () => {
    disposed = true;
    follow.stop();
    unregister();
    const lose = gl.getExtension("WEBGL_lose_context");
    if (lose) lose.loseContext();
  };
}

export default {render};
