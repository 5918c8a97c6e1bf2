// feeddrive explore: the page.  Everything is checked and computed by the server (one
// message per field, the CLI's); this script only collects the fields, starts runs, polls
// their progress and draws the results with plotly.js.
"use strict";

const $ = (id) => document.getElementById(id);
const COLORS = { screw: "#1f6feb", nut: "#8250df", guide: "#bf8700" };
// the mode bar stands vertically at the right, beside the title rather than over it; its
// camera button downloads the figure (PNG, named after the plot)
const PLOT_CONFIG = { responsive: true, displaylogo: false,
                      modeBarButtonsToRemove: ["lasso2d", "select2d"] };
function plotConfig(name) {
  return { ...PLOT_CONFIG, toImageButtonOptions: { format: "png", filename: `feeddrive-${name}`,
                                                   scale: 2 } };
}
const DEFAULT_SIGNAL = "following_error";
const GROUPS = [
  ["Drive and command", ["preset", "drive", "table_speed", "nut_speed", "position", "duration"]],
  ["Knobs", ["position_gain", "velocity_gain", "velocity_integral_gain", "friction_scale",
             "ripple_amplitude", "ripple_order", "compensation"]],
];
const FILE_BASE = "__params__";

const state = {
  info: null, fields: {}, params: null, baseName: null, preset: "wang2021",
  checkSeq: 0, runSeq: 0, checkTimer: null, simJob: null, linJob: null, critJob: null,
  lastRun: null, runs: [], signal: DEFAULT_SIGNAL, measured: null, units: {},
  machineJob: null, machineSeq: 0, machineText: "",
};

// ------------------------------------------------------------------ plumbing

async function api(method, path, body) {
  const options = { method, headers: {} };
  if (body !== undefined) {
    options.headers["Content-Type"] = "application/json";
    options.body = JSON.stringify(body);
  }
  let response;
  try {
    response = await fetch(path, options);
  } catch (err) {
    return { status: 0, data: { error: "the explorer server does not answer (stopped?)" } };
  }
  let data;
  try {
    data = await response.json();
  } catch (err) {
    data = { error: `${response.status} ${response.statusText}` };
  }
  return { status: response.status, data };
}

const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

// A press on a button leaves the field being edited, and its change is checked at once: the
// answer comes back while the button is still pressed.  Drawing it then (a message that goes
// or appears above the button) moves the button from under the pointer, the release lands
// elsewhere and the click is lost: nothing happens, nothing says why.  A check's answer waits
// for the press to end, after its click.  Only presses on what a click acts on count (a
// select's list opens on the press and may take its release).
const press = { down: false, waiting: [] };
const CLICKABLE = "button, .button, a[href], input[type=checkbox]";

function pressEnded() {
  press.down = false;
  // the click follows the pointerup in the same task: it reaches its button first
  setTimeout(() => { for (const resume of press.waiting.splice(0)) resume(); }, 0);
}

function pressOver() {
  return press.down ? new Promise((resolve) => press.waiting.push(resolve)) : Promise.resolve();
}

document.addEventListener("pointerdown", (e) => {
  if (e.button === 0 && e.target instanceof Element && e.target.closest(CLICKABLE)) {
    press.down = true;
  }
}, true);
for (const type of ["pointerup", "pointercancel"]) {
  document.addEventListener(type, pressEnded, true);
}
window.addEventListener("blur", pressEnded);  // a press whose release the page never sees

function status(text) { $("status").textContent = text; }

// a number as the text outputs print it (feeddrive.units.number_text): "∞" for an infinite
// one (a bound), "—" for a value that does not exist
function fmt(value, digits = 4, unit = "") {
  if (value === null || value === undefined || Number.isNaN(Number(value))) return "—";
  const number = Number(value);
  const text = Number.isFinite(number) ? String(parseFloat(number.toPrecision(digits)))
    : (number > 0 ? "∞" : "−∞");
  return unit ? `${text} ${unit}` : text;
}

// a loop's value: JSON has no infinity, so the server sends an infinite one (a gain margin
// without phase crossover) as null and names it in the loop's `infinite`; any other null is
// a value the loop has not (no gain crossover), left null
function loopValue(lp, name) {
  return lp[name] === null && (lp.infinite || []).includes(name) ? Infinity : lp[name];
}

// ------------------------------------------------------------------ the form

function buildForm(info) {
  const box = $("fields");
  box.textContent = "";
  for (const f of info.fields) state.fields[f.name] = f;
  for (const [title, names] of GROUPS) {
    const h = document.createElement("div");
    h.className = "group-title";
    h.textContent = title;
    box.appendChild(h);
    for (const name of names) box.appendChild(fieldRow(state.fields[name], info));
  }
}

function fieldRow(f, info) {
  const row = document.createElement("div");
  row.className = "row";
  row.id = `row-${f.name}`;
  const label = document.createElement("label");
  label.htmlFor = `f-${f.name}`;
  label.title = [f.help, f.option && `CLI ${f.option}`, f.path && `parameter ${f.path}`]
    .filter(Boolean).join(" · ");
  const text = document.createElement("span");
  text.textContent = f.label + " ";
  if (f.unit) {
    const unit = document.createElement("span");
    unit.className = "unit";
    unit.textContent = `[${f.unit}]`;
    text.appendChild(unit);
  }
  const own = document.createElement("span");
  own.className = "own";
  own.id = `own-${f.name}`;
  label.append(text, own);
  let input;
  if (f.name === "preset" || f.name === "drive" || f.name === "compensation") {
    input = document.createElement("select");
    const options = f.name === "preset" ? info.presets : f.name === "drive" ? info.drives
      : info.compensation_modes;
    for (const value of options) input.add(new Option(value, value));
  } else {
    input = document.createElement("input");
    input.type = "text";
    input.inputMode = "decimal";
    input.spellcheck = false;
  }
  input.id = `f-${f.name}`;
  input.name = f.name;
  input.addEventListener("input", () => scheduleCheck(f.name));
  input.addEventListener("change", () => scheduleCheck(f.name, true));
  const msg = document.createElement("div");
  msg.className = "msg error";
  msg.id = `msg-${f.name}`;
  const warn = document.createElement("div");
  warn.className = "msg warning";
  warn.id = `warn-${f.name}`;
  row.append(label, input, msg, warn);
  return row;
}

function presetOptions() {
  const select = $("f-preset");
  const existing = [...select.options].find((o) => o.value === FILE_BASE);
  if (state.params) {
    const label = `file: ${state.baseName || "imported"}`;
    if (existing) existing.text = label;
    else select.add(new Option(label, FILE_BASE), 0);
    select.value = FILE_BASE;
  } else if (existing) {
    existing.remove();
  }
}

function collect(withKnobs = true) {
  const settings = {};
  for (const name of Object.keys(state.fields)) {
    const input = $(`f-${name}`);
    if (!input) continue;
    if (name === "preset") {
      if (input.value === FILE_BASE) settings.params = state.params;
      settings.preset = input.value === FILE_BASE ? state.preset : input.value;
      continue;
    }
    if (!withKnobs && state.fields[name].group === "knob") continue;
    settings[name] = input.value;
  }
  return settings;
}

function fill(settings) {
  if (!settings) return;
  if ("params" in settings || settings.preset) {
    state.params = settings.params || null;
    if (settings.preset) state.preset = settings.preset;
  }
  for (const [name, value] of Object.entries(settings)) {
    const input = $(`f-${name}`);
    if (!input || name === "preset") continue;
    input.value = value;
  }
  $("f-preset").value = state.preset;
  presetOptions();
}

function showUnits(units) {
  if (!units) return;
  state.units = units;
  for (const [name, unit] of Object.entries(units)) {
    const span = document.querySelector(`#row-${name} .unit`);
    if (span) span.textContent = unit ? `[${unit}]` : "";
  }
}

function showMessages(result) {
  showUnits(result.units);
  const errors = result.errors || {};
  const warnings = result.warnings || {};
  for (const name of Object.keys(state.fields)) {
    const input = $(`f-${name}`);
    $(`msg-${name}`).textContent = errors[name] || "";
    $(`warn-${name}`).textContent = warnings[name] ? `warning: ${warnings[name]}` : "";
    input.classList.toggle("invalid", Boolean(errors[name]));
    const f = state.fields[name];
    if (f.group === "knob" && result.base) {
      const own = result.base[name];
      $(`own-${name}`).textContent = own === undefined ? "" : `set: ${own}`;
      input.classList.toggle("changed", (result.overrides || []).includes(name));
    }
    input.disabled = (result.disabled || []).includes(name);
  }
  $("msg-params").textContent = errors.params || "";
  $("msg-import").textContent = errors.import || "";
  if (result.base_name) state.baseName = result.base_name;
  presetOptions();
  if (result.query !== undefined) {
    history.replaceState(null, "", `${location.pathname}?${result.query}`);
  }
}

function scheduleCheck(name, now = false) {
  clearTimeout(state.checkTimer);
  const knobsReset = name === "preset";
  if (knobsReset && $("f-preset").value !== FILE_BASE) {
    state.params = null;
    state.preset = $("f-preset").value;
  }
  state.checkTimer = setTimeout(() => check(!knobsReset), now ? 0 : 350);
}

async function check(withKnobs = true) {
  const seq = ++state.checkSeq;
  const r = await api("POST", "/api/check", { settings: collect(withKnobs) });
  await pressOver();
  if (seq !== state.checkSeq) return false;
  if (r.status !== 200) {
    $("msg-run").textContent = r.data.error || "the check failed";
    return false;
  }
  if (!withKnobs) fill(r.data.settings);
  showMessages(r.data);
  const ok = Object.keys(r.data.errors).length === 0;
  if (ok && $("msg-run").textContent.startsWith("fix")) $("msg-run").textContent = "";
  if (ok && $("auto").checked) run();
  return ok;
}

// ------------------------------------------------------------------ runs

function showProgress(box, job) {
  // a bar for work longer than 0.3 s; a critical-speed search shows its Cancel at once
  const after = job && job.kind === "critical" ? 0 : 0.3;
  if (!job || job.state !== "running" || job.elapsed_s < after) {
    box.hidden = true;
    return;
  }
  box.hidden = false;
  const bar = box.querySelector(".bar");
  const p = job.progress;
  let fraction = null;
  if (job.kind === "simulate" && p.done > 0 && p.total > 0) {
    fraction = Math.min(1, p.done / p.total);  // simulated time reached, after each chunk
  } else if (job.kind === "simulate") {
    if (job.expected_s) fraction = Math.min(0.97, job.elapsed_s / job.expected_s);
  } else if (p.total > 0) {
    fraction = Math.min(1, p.done / p.total);
  }
  box.classList.toggle("indeterminate", fraction === null);
  bar.style.width = fraction === null ? "" : `${(100 * fraction).toFixed(1)}%`;
  const left = job.kind === "simulate" && job.expected_s
    ? ` of about ${Math.max(job.expected_s, job.elapsed_s).toFixed(1)} s` : "";
  box.querySelector(".text").textContent =
    `${p.text || "working"} · ${job.elapsed_s.toFixed(1)} s${left}`;
}

async function poll(id, box, stale) {
  let wait = 25;
  for (;;) {
    await sleep(wait);
    wait = 100;
    const r = await api("GET", `/api/jobs/${id}`);
    if (stale()) return null;
    if (r.status !== 200) {
      box.hidden = true;
      return { state: "failed", error: r.data.error };
    }
    showProgress(box, r.data);
    if (r.data.state !== "running") {
      box.hidden = true;
      return r.data;
    }
  }
}

function cancelJob(id) {
  if (id) api("POST", `/api/jobs/${id}/cancel`, {});
}

async function run() {
  const settings = collect();
  const clicked = performance.now();
  const seq = ++state.runSeq;
  cancelJob(state.simJob);
  cancelJob(state.linJob);
  $("msg-run").textContent = "";
  $("verdict").classList.add("stale");
  const r = await api("POST", "/api/jobs", { kind: "simulate", settings });
  if (seq !== state.runSeq) return;
  if (r.status === 422) {
    showMessages(r.data);
    $("msg-run").textContent = "fix the marked fields to run (the plots show the last run)";
    return;
  }
  if (r.status !== 202) {
    $("msg-run").textContent = r.data.error || `the run was refused (${r.status})`;
    return;
  }
  showMessages(r.data.check);
  state.simJob = r.data.id;
  status("running…");
  const job = await poll(r.data.id, $("run-progress"), () => seq !== state.runSeq);
  if (!job || seq !== state.runSeq) return;
  state.simJob = null;
  if (job.state === "done") {
    renderRun(job.result);
    addRun(job.result, settings);
    const shown = (performance.now() - clicked) / 1000;
    $("verdict").dataset.shownAfterS = shown.toFixed(3);
    status(`shown ${shown.toFixed(2)} s after the click (solver ${
      job.result.summary.solver.wall_time_s.toFixed(2)} s)`);
    runLinear(settings, seq);
  } else if (job.state === "failed") {
    const box = job.field ? $(`msg-${job.field}`) : $("msg-run");
    box.textContent = job.error;
    clearRun(`the run failed: ${job.error}`);
    status("the run failed");
  } else {
    status("run cancelled");
  }
}

async function runLinear(settings, seq) {
  const r = await api("POST", "/api/jobs", { kind: "linear", settings });
  if (seq !== state.runSeq || r.status !== 202) return;
  state.linJob = r.data.id;
  const job = await poll(r.data.id, $("linear-progress"), () => seq !== state.runSeq);
  if (!job || seq !== state.runSeq) return;
  state.linJob = null;
  $("msg-linear").textContent = "";
  if (job.state === "done") renderLinear(job.result);
  else if (job.state === "failed") {
    $("msg-linear").textContent = `linear analysis: ${job.error}`;
    Plotly.purge($("plot-band"));
    Plotly.purge($("plot-poles"));
    Plotly.purge($("plot-bode"));
  }
}

function clearRun(text) {
  // a failed run's page shows no earlier run's results under its message
  state.lastRun = null;
  setVerdict(null, text);
  $("run-facts").textContent = "";
  $("linear-facts").textContent = "";
  $("settings-diff").textContent = "";
  for (const id of ["plot-speed", "plot-friction", "plot-signal", "plot-band", "plot-poles",
                    "plot-bode"]) {
    Plotly.purge($(id));
  }
  for (const id of ["download-csv", "download-mat"]) $(id).hidden = true;
}

function setVerdict(verdict, text) {
  const box = $("verdict");
  box.classList.remove("stale");
  box.dataset.verdict = verdict ? verdict.verdict : "";
  box.dataset.kind = verdict ? verdict.kind : "";
  box.textContent = "";
  if (!verdict) {
    box.textContent = text;
    return;
  }
  const head = document.createElement("span");
  head.className = "head";
  head.textContent = verdict.verdict.toUpperCase() +
    (verdict.kind !== verdict.verdict ? ` — ${verdict.kind}` : "");
  const detail = document.createElement("span");
  detail.className = "detail";
  detail.textContent = `: ${verdict.text}`;
  box.append(head, detail);
}

// ------------------------------------------------------------------ drawing

function layout(title, xTitle, yTitle, extra = {}) {
  return {
    title: { text: title, font: { size: 13 } },
    margin: { l: 62, r: 40, t: 38, b: 58 },
    modebar: { orientation: "v" },
    xaxis: { title: { text: xTitle }, zeroline: false, ...(extra.xaxis || {}) },
    yaxis: { title: { text: yTitle }, ...(extra.yaxis || {}) },
    legend: { orientation: "h", y: -0.28, font: { size: 11 } },
    hovermode: "closest", shapes: extra.shapes || [], annotations: extra.annotations || [],
    uirevision: extra.uirevision,
  };
}

function renderRun(res) {
  state.lastRun = res;
  setVerdict(res.verdict);
  const s = res.summary;
  const what = `${res.drive.toUpperCase()} at ${fmt(res.table_speed_mm_s)} mm/s` +
    (res.nut_driven ? `, hollow motor ${fmt(res.nut_speed_mm_s)} mm/s` : "");
  $("run-facts").textContent =
    `${what}, ${fmt(res.duration_s)} s simulated (${res.parameter_set}) · mean table speed ` +
    `${fmt(s.mean_table_speed_mm_s)} mm/s · following error max ` +
    `${fmt(s.following_error_max_um, 3)} µm · judged on ${fmt(s.window_s[0], 3)}–` +
    `${fmt(s.window_s[1], 3)} s (feeddrive simulate's window rule says ${s.verdict}: ripple ≤ 50 %, stick ≤ 2 %) · ` +
    `solver ${s.solver.steps} steps`;
  const t = res.traces;
  const hover = (name) => `t = %{x:.4f} s<br>${name} = %{y:.4g} mm/s<extra></extra>`;
  const traces = [
    { x: t.time_s, y: t.table_speed_mm_s, name: "table speed", type: "scatter",
      mode: "lines", line: { color: "#1f6feb", width: 1.5 }, hovertemplate: hover("v") },
    { x: t.time_s, y: t.table_speed_reference_mm_s, name: "command", type: "scatter",
      mode: "lines", line: { color: "#1d2330", dash: "dash", width: 1.2 },
      hovertemplate: hover("command") },
  ];
  if (t.screw_linear_speed_mm_s) {
    traces.push({ x: t.time_s, y: t.screw_linear_speed_mm_s, name: "screw motor (× H)",
                  type: "scatter", mode: "lines", visible: "legendonly",
                  line: { color: COLORS.screw, width: 1 }, hovertemplate: hover("screw") });
  }
  if (t.nut_linear_speed_mm_s && res.nut_driven) {
    traces.push({ x: t.time_s, y: t.nut_linear_speed_mm_s, name: "hollow motor (× H)",
                  type: "scatter", mode: "lines", visible: "legendonly",
                  line: { color: COLORS.nut, width: 1 }, hovertemplate: hover("hollow") });
  }
  if (state.measured) {
    traces.push({ x: state.measured.time_s, y: state.measured.speed_mm_s, type: "scatter",
                  mode: "lines", name: `measured (${state.measured.name})`,
                  line: { color: "#1a7f37", width: 1.2 },
                  hovertemplate: hover("measured") });
  }
  const l = layout(`table speed: ${what}`, "time [s]", "speed [mm/s]",
                   { uirevision: "speed" });
  Plotly.react($("plot-speed"), traces, l, plotConfig("table-speed"));
  renderFriction(res.friction);
}

function renderFriction(fr) {
  const traces = [];
  const shapes = [];
  for (const site of fr.sites) {
    const color = COLORS[site.site] || "#444";
    const bands = site.negative_slope_mm_s.map((b) => `${fmt(b[0], 3)}…${fmt(b[1], 3)}`);
    traces.push({
      x: site.speed_mm_s, y: site.force_n, type: "scatter", mode: "lines",
      name: `${site.site} (${site.law})`, line: { color, width: 1.6 },
      hovertemplate: `${site.site}: v = %{x:.4g} mm/s<br>F = %{y:.4g} N<extra></extra>`,
    });
    for (const [a, b] of site.negative_slope_mm_s) {
      shapes.push({ type: "rect", xref: "x", yref: "paper", x0: a, x1: b, y0: 0, y1: 1,
                    fillcolor: color, opacity: 0.12, line: { width: 0 }, layer: "below" });
    }
    if (site.operating_speed_mm_s !== null && site.operating_force_n !== null) {
      traces.push({
        x: [site.operating_speed_mm_s], y: [site.operating_force_n], type: "scatter",
        mode: "markers", name: `${site.site} runs at ${fmt(site.operating_speed_mm_s)} mm/s`,
        marker: { color, size: 10, symbol: "diamond", line: { color: "#fff", width: 1 } },
        hovertemplate: `${site.site} in this run: v = %{x:.4g} mm/s<br>F = %{y:.4g} N` +
          `<br>falls on ${bands.join(", ") || "no band"} mm/s<extra></extra>`,
      });
    }
  }
  Plotly.react($("plot-friction"), traces,
               layout("steady friction (shaded: where it falls with speed)",
                      "sliding speed [mm/s]", "friction force [N]",
                      { shapes, uirevision: "friction" }), plotConfig("friction"));
}

function renderLinear(res) {
  const band = res.band;
  const v = Math.abs(res.table_speed_mm_s);
  const shapes = band.unstable_bands_mm_s.map(([a, b]) => ({
    type: "rect", xref: "x", yref: "paper", x0: a, x1: b, y0: 0, y1: 1,
    fillcolor: "#b42318", opacity: 0.13, line: { width: 0 }, layer: "below" }));
  shapes.push({ type: "line", xref: "x", yref: "paper", x0: v, x1: v, y0: 0, y1: 1,
                line: { color: "#1d2330", dash: "dot", width: 1.2 } });
  const traces = [{
    x: band.speeds_mm_s, y: band.max_real_part_1_per_s, type: "scatter", mode: "lines+markers",
    name: "rightmost pole", marker: { size: 4 }, line: { color: "#b42318", width: 1.4 },
    customdata: band.frequency_hz,
    hovertemplate: "v = %{x:.4g} mm/s<br>max Re(s) = %{y:.4g} 1/s<br>" +
      "mode %{customdata:.3g} Hz<extra></extra>",
  }];
  const bandText = band.unstable_bands_mm_s.length
    ? band.unstable_bands_mm_s.map(([a, b]) => `${fmt(a, 3)}–${fmt(b, 3)} mm/s`).join(", ")
    : "none in the scanned range";
  Plotly.react($("plot-band"), traces,
               layout(`linear stability band (shaded: unstable sliding): ${bandText}`,
                      "table speed [mm/s]", "rightmost pole real part [1/s]",
                      { xaxis: { type: "log" }, shapes, uirevision: "band",
                        annotations: [{ x: Math.log10(v), y: 1, xref: "x", yref: "paper",
                                        text: "this run", showarrow: false, yanchor: "bottom",
                                        font: { size: 10 } }] }), plotConfig("band"));
  const rigid = res.poles.filter((p) => p.kind === "rigid-body");
  const poles = res.poles.filter((p) => p.kind !== "rigid-body");
  const xs = poles.map((p) => p.real_1_per_s);
  const ys = poles.map((p) => p.frequency_hz * Math.sign(p.imag_rad_per_s || 0));
  const slow = poles.filter((p) => p.frequency_hz < 200).map((p) => p.real_1_per_s);
  const lo = Math.min(...(slow.length ? slow : xs));
  const hi = Math.max(...xs.filter((x) => x >= lo), 0);
  const pad = 0.08 * (hi - lo || 1);
  const rigidTrace = {
    x: rigid.map(() => 0), y: rigid.map(() => 0), type: "scatter", mode: "markers",
    name: `rigid-body (free motion, ${rigid.length})`,
    marker: { size: 11, symbol: "circle-open", color: "#888" },
    hovertemplate: "rigid-body pole: a free motion no loop holds<br>(an eigenvalue 0; " +
      "no damping ratio)<extra></extra>",
  };
  Plotly.react($("plot-poles"), [...(rigid.length ? [rigidTrace] : []), {
    x: xs, y: poles.map((p) => p.imag_rad_per_s / (2 * Math.PI)), type: "scatter",
    mode: "markers", name: "poles", showlegend: rigid.length > 0,
    marker: { size: 9, symbol: "x", color: xs.map((x) => (x > 0 ? "#b42318" : "#1f6feb")) },
    customdata: poles.map((p) => [p.frequency_hz, p.damping_ratio]),
    hovertemplate: "Re = %{x:.4g} 1/s<br>Im/2π = %{y:.4g} Hz<br>|s|/2π = " +
      "%{customdata[0]:.4g} Hz, ζ = %{customdata[1]:.3g}<extra></extra>",
  }], layout(`loop poles at ${fmt(res.table_speed_mm_s)} mm/s, ${res.friction}`,
             "real part [1/s]", "imaginary part / 2π [Hz]",
             { xaxis: { range: [lo - pad, hi + pad] }, uirevision: `poles-${ys.length}`,
               shapes: [{ type: "line", xref: "x", yref: "paper", x0: 0, x1: 0, y0: 0, y1: 1,
                          line: { color: "#888", width: 1 } }] }), plotConfig("poles"));
  renderBode(res.bode || [], res.friction);
  const d = res.least_damped_mode;
  const loops = res.loops.map((lp) => `${lp.loop}: phase margin ` +
    `${fmt(lp.phase_margin_deg, 3, "°")}, gain margin ` +
    `${fmt(loopValue(lp, "gain_margin_db"), 3, "dB")}`)
    .join(" · ");
  const notes = (res.notes || []).join(" · ");
  $("linear-facts").textContent =
    `Steady sliding at ${fmt(res.table_speed_mm_s)} mm/s is linearly ` +
    `${res.inside_band ? "UNSTABLE (inside the band)" : "stable"}; ${res.friction} ` +
    "(feeddrive loops: without friction unless --with-friction): least-damped mode " +
    `${fmt(d.frequency_hz, 3)} Hz, ζ = ${fmt(d.damping_ratio, 3)} · ${loops}` +
    (rigid.length ? ` · ${rigid.length} rigid-body pole(s), not a mode` : "") +
    (notes ? ` · ${notes}` : "");
}


// ------------------------------------------------------------------ loops: Bode plot

function renderBode(bode, friction) {
  if (!bode.length) {
    Plotly.purge($("plot-bode"));
    return;
  }
  const colors = ["#1f6feb", "#bf8700", "#8250df", "#1a7f37"];
  const traces = [];
  const shapes = [
    { type: "line", xref: "paper", yref: "y", x0: 0, x1: 1, y0: 0, y1: 0,
      line: { color: "#1d2330", width: 1 } },
    { type: "line", xref: "paper", yref: "y2", x0: 0, x1: 1, y0: -180, y1: -180,
      line: { color: "#1d2330", width: 1 } },
  ];
  const annotations = [];
  bode.forEach((lp, k) => {
    const color = colors[k % colors.length];
    const pm = lp.phase_margin_deg === null ? "" : `, PM ${fmt(lp.phase_margin_deg, 3)}°`;
    const gain = loopValue(lp, "gain_margin_db");
    const gm = gain === null ? "" : `, GM ${fmt(gain, 3, "dB")}`;
    traces.push({ x: lp.frequency_hz, y: lp.magnitude_db, type: "scatter", mode: "lines",
                  name: `${lp.loop}${pm}${gm}`, line: { color, width: 1.5 }, yaxis: "y",
                  legendgroup: lp.loop,
                  hovertemplate: `${lp.loop}: %{x:.4g} Hz, |L| = %{y:.4g} dB<extra></extra>` });
    traces.push({ x: lp.frequency_hz, y: lp.phase_deg, type: "scatter", mode: "lines",
                  name: lp.loop, showlegend: false, line: { color, width: 1.5 }, yaxis: "y2",
                  legendgroup: lp.loop,
                  hovertemplate: `${lp.loop}: %{x:.4g} Hz, ∠L = %{y:.4g}°<extra></extra>` });
    if (lp.crossover_hz !== null) {
      const fc = lp.crossover_hz;
      shapes.push({ type: "line", xref: "x", yref: "paper", x0: fc, x1: fc, y0: 0, y1: 1,
                    line: { color, width: 1, dash: "dot" } });
      traces.push({ x: [fc], y: [0], type: "scatter", mode: "markers", yaxis: "y",
                    showlegend: false, marker: { color, size: 8 }, legendgroup: lp.loop,
                    hovertemplate: `${lp.loop}: crossover ${fmt(fc, 4)} Hz<extra></extra>` });
      if (lp.phase_margin_deg !== null) {
        annotations.push({ x: Math.log10(fc), y: -180 + lp.phase_margin_deg, xref: "x",
                           yref: "y2", ax: 0, ay: 0, text: `PM ${fmt(lp.phase_margin_deg, 3)}°`,
                           showarrow: false, xanchor: "left", font: { size: 10, color } });
      }
    }
  });
  const l = layout(`loop gains L(jω), ${friction} (loop broken at its command; crossover ` +
                   "dotted)",
                   "frequency [Hz]", "|L| [dB]", { shapes, annotations, uirevision: "bode" });
  l.xaxis.type = "log";
  l.xaxis.anchor = "y2";
  l.yaxis = { title: { text: "|L| [dB]" }, domain: [0.55, 1] };
  l.yaxis2 = { title: { text: "∠L [°]" }, domain: [0, 0.45] };
  l.legend = { orientation: "h", y: -0.18, font: { size: 11 } };
  Plotly.react($("plot-bode"), traces, l, plotConfig("bode"));
}

// ------------------------------------------------------------------ runs: signals, A/B

function runLabel(run) {
  const s = run.settings;
  return `${run.id}: ${String(s.drive).toUpperCase()} ${s.table_speed} mm/s, ${s.duration} s` +
    (s.preset ? ` (${s.preset})` : "");
}

function addRun(res, settings) {
  if (!res.run_id) return;
  const run = { id: res.run_id, settings: { ...settings } };
  delete run.settings.params;
  state.runs = [run, ...state.runs.filter((r) => r.id !== run.id)].slice(0, 10);
  $("download-csv").href = `/api/runs/${run.id}/data.csv`;
  $("download-mat").href = `/api/runs/${run.id}/data.mat`;
  $("download-csv").hidden = false;
  $("download-mat").hidden = false;
  const compare = $("compare");
  const keep = compare.value;
  compare.textContent = "";
  compare.add(new Option("(no other run)", ""));
  for (const r of state.runs.slice(1)) compare.add(new Option(runLabel(r), r.id));
  compare.value = [...compare.options].some((o) => o.value === keep) ? keep : "";
  compare.disabled = state.runs.length < 2;
  loadSignals(run.id);
}

async function loadSignals(id) {
  const r = await api("GET", `/api/runs/${id}/signals`);
  if (r.status !== 200 || !state.runs.length || state.runs[0].id !== id) return;
  const select = $("signal");
  select.textContent = "";
  for (const sig of r.data.signals) {
    select.add(new Option(`${sig.name} [${sig.unit}] — ${sig.label}`, sig.name));
  }
  const names = r.data.signals.map((x) => x.name);
  select.value = names.includes(state.signal) ? state.signal : names[0];
  state.signal = select.value;
  select.disabled = false;
  renderSignal();
}

function settingsDiff(a, b) {
  const rows = [];
  for (const key of new Set([...Object.keys(a), ...Object.keys(b)])) {
    if (String(a[key] ?? "") !== String(b[key] ?? "")) {
      const f = state.fields[key];
      const unit = state.units[key] || (f && f.unit) || "";
      rows.push(`${f ? f.label : key}: A ${a[key] ?? "—"} → B ${b[key] ?? "—"}` +
                (unit ? ` [${unit}]` : ""));
    }
  }
  return rows;
}

async function renderSignal() {
  const name = $("signal").value;
  if (!name || !state.runs.length) return;
  state.signal = name;
  const a = state.runs[0];
  const bId = $("compare").value;
  const b = state.runs.find((r) => r.id === bId);
  const [ra, rb] = await Promise.all([
    api("GET", `/api/runs/${a.id}/signal?name=${encodeURIComponent(name)}`),
    b ? api("GET", `/api/runs/${b.id}/signal?name=${encodeURIComponent(name)}`) : null,
  ]);
  // a call overtaken by a newer choice of signal or of run B draws nothing: it would
  // overwrite the newer plot and A/B settings line with the older ones
  if (ra.status !== 200 || $("signal").value !== name || $("compare").value !== bId) return;
  const sig = ra.data;
  const hover = (who) => `${who}: t = %{x:.4f} s<br>${name} = %{y:.5g} ${sig.unit}<extra></extra>`;
  const traces = [{ x: sig.time_s, y: sig.values, type: "scatter", mode: "lines",
                    name: `A: ${runLabel(a)}`, line: { color: "#1f6feb", width: 1.4 },
                    hovertemplate: hover("A") }];
  const diff = $("settings-diff");
  diff.textContent = "";
  if (b && rb && rb.status === 200) {
    traces.push({ x: rb.data.time_s, y: rb.data.values, type: "scatter", mode: "lines",
                  name: `B: ${runLabel(b)}`, line: { color: "#b42318", width: 1.2, dash: "dash" },
                  hovertemplate: hover("B") });
    const rows = settingsDiff(a.settings, b.settings);
    diff.textContent = rows.length ? `A/B settings: ${rows.join(" · ")}`
      : "A/B settings: the same";
  } else if (b && rb) {
    diff.textContent = `run B: ${rb.data.error || "not available"}`;
  }
  const m = state.measured;
  if (m && (name === "table_speed" || name === "table_position")) {
    traces.push({ x: m.time_s, y: name === "table_speed" ? m.speed_mm_s : m.position_mm,
                  type: "scatter", mode: "lines", name: `measured (${m.name})`,
                  line: { color: "#1a7f37", width: 1.2 }, hovertemplate: hover("measured") });
  }
  Plotly.react($("plot-signal"), traces,
               layout(`${sig.label} [${sig.unit}]`, "time [s]", `${name} [${sig.unit}]`,
                      { uirevision: `signal-${name}` }), plotConfig(`signal-${name}`));
  $("plot-signal").dataset.signal = name;
  $("plot-signal").dataset.traces = String(traces.length);
}

async function loadMeasured(file) {
  $("msg-measured").textContent = "";
  const text = await file.text();
  const r = await api("POST", "/api/measured", { csv: text, name: file.name });
  if (r.status !== 200) {
    $("msg-measured").textContent = r.data.error || `refused (${r.status})`;
    return;
  }
  state.measured = r.data;
  $("measured-clear").hidden = false;
  status(`measured ${r.data.name}: ${r.data.samples} samples (speed from ${r.data.speed_from})`);
  if (state.lastRun) renderRun(state.lastRun);
  renderSignal();
}

// ------------------------------------------------------------------ critical speed

async function critical() {
  if (state.critJob) return;
  const r = await api("POST", "/api/jobs", { kind: "critical", settings: collect() });
  if (r.status !== 202) {  // refused: said here, the search's last result no longer stands
    const box = $("critical-result");
    box.dataset.state = "refused";
    box.title = "";
    if (r.status === 422) showMessages(r.data);
    box.textContent = r.status === 422 ? "fix the marked fields to search"
      : r.data.error || `refused (${r.status})`;
    return;
  }
  state.critJob = r.data.id;
  showProgress($("critical-progress"), r.data);
  $("critical").disabled = true;
  $("critical-result").textContent = "";
  $("critical-result").dataset.state = "running";
  const job = await poll(r.data.id, $("critical-progress"), () => false);
  state.critJob = null;
  $("critical").disabled = false;
  const box = $("critical-result");
  box.dataset.state = job.state;
  if (job.state === "done") {
    const c = job.result;
    box.textContent = `critical speed ${c.display} (${c.drive.toUpperCase()}, ` +
      `${c.trials.length} trials from rest, ${fmt(c.simulated_time_s, 3)} s simulated); ` +
      `creeping bands [mm/s]: ${c.bands_text}` +
      (c.integration_error_text ? `; ${c.integration_error_text}` : "");
    box.title = c.protocol;
  } else if (job.state === "cancelled") {
    box.textContent = "cancelled";
  } else {
    box.textContent = job.error || "failed";
  }
}

// ------------------------------------------------------------------ sharing

async function exportToml() {
  const r = await api("POST", "/api/export", { settings: collect() });
  if (r.status !== 200) {
    showMessages(r.data);
    return;
  }
  const blob = new Blob([r.data.toml], { type: "application/toml" });
  const a = document.createElement("a");
  a.href = URL.createObjectURL(blob);
  a.download = r.data.filename;
  document.body.appendChild(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 10000);
  status(`exported ${r.data.filename}`);
}

async function importToml(file) {
  const text = await file.text();
  const r = await api("POST", "/api/import", { toml: text, settings: collect() });
  $("msg-import").textContent = "";
  if (r.status !== 200) {
    $("msg-import").textContent = (r.data.errors && r.data.errors.import) || r.data.error;
    return;
  }
  fill(r.data.settings);
  showMessages(r.data);
  status(`imported ${file.name}`);
  if (Object.keys(r.data.errors).length === 0 && $("auto").checked) run();
}

async function copyLink() {
  try {
    await navigator.clipboard.writeText(location.href);
    status("link copied");
  } catch (err) {
    $("msg-import").textContent = `copy this address: ${location.href}`;
  }
}

// ------------------------------------------------------------------ machine: XY path

const MACHINE_FILE = "__file__";

function machineForm(info) {
  const select = $("machine-name");
  select.replaceChildren(...info.machines.map((name) => new Option(name, name)));
  select.value = info.machine_defaults.machine;
  $("machine-radius").value = info.machine_defaults.radius;
  $("machine-feed").value = info.machine_defaults.feed;
}

async function loadMachineFile(file) {
  state.machineText = await file.text();
  const select = $("machine-name");
  let opt = select.querySelector(`option[value="${MACHINE_FILE}"]`);
  if (!opt) {
    opt = new Option("", MACHINE_FILE);
    select.add(opt);
  }
  opt.textContent = `file: ${file.name}`;
  select.value = MACHINE_FILE;
  status(`machine file ${file.name} loaded`);
}

async function runMachine() {
  const name = $("machine-name").value;
  const body = {
    machine: name === MACHINE_FILE ? state.machineText : name,
    radius: $("machine-radius").value, feed: $("machine-feed").value,
  };
  $("msg-machine").textContent = "";
  cancelJob(state.machineJob);
  const seq = ++state.machineSeq;
  const r = await api("POST", "/api/machine", body);
  if (seq !== state.machineSeq) return;
  if (r.status !== 202) {
    $("msg-machine").textContent =
      (r.data.errors && Object.values(r.data.errors).join("; ")) || r.data.error ||
      `the run was refused (${r.status})`;
    return;
  }
  state.machineJob = r.data.id;
  const job = await poll(r.data.id, $("machine-progress"), () => seq !== state.machineSeq);
  if (!job) return;
  if (job.state === "done") renderMachine(job.result);
  else if (job.state === "failed") $("msg-machine").textContent = job.error;
}

function renderMachine(res) {
  const p = res.path;
  const s = res.summary;
  const [a, b] = res.axes;
  const parts = res.couplings.length ? `, parts ${res.couplings.join(", ")}` : "";
  $("machine-facts").textContent =
    `machine ${res.machine} (axes ${a}, ${b}${parts}), ${fmt(res.duration_s)} s simulated · ` +
    `contour error ${fmt(s.contour_error_min_um)} … ${fmt(s.contour_error_max_um)} µm · ` +
    `mean radius reduction ${fmt(s.radius_reduction_um)} µm · roundness ` +
    `${fmt(s.roundness_um)} µm`;
  const xy = [
    { x: p.x_reference_mm, y: p.y_reference_mm, name: "command", type: "scatter",
      mode: "lines", line: { color: "#1d2330", dash: "dash", width: 1.2 } },
    { x: p.x_mm, y: p.y_mm, name: "actual", type: "scatter", mode: "lines",
      line: { color: "#1f6feb", width: 1.5 } },
  ];
  Plotly.react($("plot-xy"), xy,
               layout(`XY path: ${res.machine}`, `${a} [mm]`, `${b} [mm]`,
                      { yaxis: { scaleanchor: "x" }, uirevision: "xy" }),
               plotConfig("xy-path"));
  const err = [{ x: p.time_s, y: p.contour_error_um, name: "contour error", type: "scatter",
                 mode: "lines", line: { color: "#cf222e", width: 1.2 },
                 hovertemplate: "t = %{x:.4f} s<br>e = %{y:.4g} µm<extra></extra>" }];
  Plotly.react($("plot-contour"), err,
               layout("contour error (positive outside the path)", "time [s]",
                      "contour error [µm]", { uirevision: "contour" }),
               plotConfig("contour-error"));
}

// ------------------------------------------------------------------ start

async function waitReady() {
  for (;;) {
    const r = await api("GET", "/api/info");
    if (r.status === 200 && r.data.ready) {
      if ($("status").textContent.startsWith("preparing")) status("ready");
      return;
    }
    await sleep(500);
  }
}

async function start() {
  const r = await api("GET", "/api/info");
  if (r.status !== 200) {
    status(r.data.error || "the server did not answer");
    return;
  }
  const info = r.data;
  state.info = info;
  buildForm(info);
  $("critical-note").textContent =
    `Searches from rest as feeddrive creep does: about ${info.critical_trials} trials, ` +
    "each 12 s or longer until decided.";
  let first;
  if (location.search.length > 1) {
    first = await api("GET", `/api/state${location.search}`);
  } else {
    first = await api("POST", "/api/check", { settings: info.initial });
  }
  fill(first.data.settings);
  showMessages(first.data);
  if (!info.ready) {
    status("preparing the solver (the first start after an install compiles it)…");
    waitReady();
  } else {
    status("ready");
  }
  machineForm(info);
  $("machine-run").addEventListener("click", runMachine);
  for (const id of ["machine-radius", "machine-feed"]) {
    $(id).addEventListener("keydown", (e) => {  // Enter runs the circle, not the drive
      if (e.key === "Enter") { e.preventDefault(); runMachine(); }
    });
  }
  $("machine-cancel").addEventListener("click", () => {
    cancelJob(state.machineJob);
    state.machineSeq++;
    $("machine-progress").hidden = true;
  });
  $("machine-file").addEventListener("change", (e) => {
    if (e.target.files.length) loadMachineFile(e.target.files[0]);
    e.target.value = "";
  });
  $("controls").addEventListener("submit", (e) => { e.preventDefault(); run(); });
  $("run-cancel").addEventListener("click", () => {
    state.runSeq++;
    cancelJob(state.simJob);
    $("run-progress").hidden = true;
    status("run cancelled");
  });
  $("critical").addEventListener("click", critical);
  $("critical-cancel").addEventListener("click", () => {
    cancelJob(state.critJob);
    $("critical-progress").querySelector(".text").textContent = "cancelling after this trial…";
  });
  $("export").addEventListener("click", exportToml);
  $("import-file").addEventListener("change", (e) => {
    const file = e.target.files[0];
    if (file) importToml(file);
    e.target.value = "";
  });
  $("copy-link").addEventListener("click", copyLink);
  $("signal").addEventListener("change", renderSignal);
  $("compare").addEventListener("change", renderSignal);
  $("measured-file").addEventListener("change", (e) => {
    const file = e.target.files[0];
    if (file) loadMeasured(file);
    e.target.value = "";
  });
  $("measured-clear").addEventListener("click", () => {
    state.measured = null;
    $("measured-clear").hidden = true;
    if (state.lastRun) renderRun(state.lastRun);
    renderSignal();
  });
  showUnits(info.units);
  document.body.dataset.ready = "yes";
  if (Object.keys(first.data.errors || {}).length === 0) run();
}

window.addEventListener("DOMContentLoaded", start);
