// feeddrive explore: the page.  Everything is checked and computed by the server (one
// message per field, the CLI's); this script only collects the fields, starts runs, polls
// their progress and draws the results with plotly.js.
"use strict";

const $ = (id) => document.getElementById(id);
const COLORS = { screw: "#1f6feb", nut: "#8250df", guide: "#bf8700" };
const PLOT_CONFIG = { responsive: true, displaylogo: false,
                      modeBarButtonsToRemove: ["lasso2d", "select2d"] };
const GROUPS = [
  ["Drive and command", ["preset", "drive", "table_speed", "nut_speed", "position", "duration"]],
  ["Knobs", ["position_gain", "velocity_gain", "velocity_integral_gain", "friction_scale",
             "ripple_amplitude", "ripple_order", "compensation"]],
];
const FILE_BASE = "__params__";

const state = {
  info: null, fields: {}, params: null, baseName: null, preset: "wang2021",
  checkSeq: 0, runSeq: 0, checkTimer: null, simJob: null, linJob: null, critJob: null,
  lastRun: null,
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

function status(text) { $("status").textContent = text; }

function fmt(value, digits = 4, unit = "") {
  if (value === null || value === undefined) return "—";
  const text = String(parseFloat(Number(value).toPrecision(digits)));
  return unit ? `${text} ${unit}` : text;
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

function showMessages(result) {
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
  if (job.kind === "simulate") {
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
    const shown = (performance.now() - clicked) / 1000;
    $("verdict").dataset.shownAfterS = shown.toFixed(3);
    status(`shown ${shown.toFixed(2)} s after the click (solver ${
      job.result.summary.solver.wall_time_s.toFixed(2)} s)`);
    runLinear(settings, seq);
  } else if (job.state === "failed") {
    const box = job.field ? $(`msg-${job.field}`) : $("msg-run");
    box.textContent = job.error;
    setVerdict(null, "the run failed");
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
  }
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
    margin: { l: 62, r: 15, t: 38, b: 58 },
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
    (res.drive === "ddfs" ? `, hollow motor ${fmt(res.nut_speed_mm_s)} mm/s` : "");
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
  if (t.nut_linear_speed_mm_s && res.drive === "ddfs") {
    traces.push({ x: t.time_s, y: t.nut_linear_speed_mm_s, name: "hollow motor (× H)",
                  type: "scatter", mode: "lines", visible: "legendonly",
                  line: { color: COLORS.nut, width: 1 }, hovertemplate: hover("hollow") });
  }
  const l = layout(`table speed: ${what}`, "time [s]", "speed [mm/s]",
                   { uirevision: "speed" });
  Plotly.react($("plot-speed"), traces, l, PLOT_CONFIG);
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
                      { shapes, uirevision: "friction" }), PLOT_CONFIG);
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
                                        font: { size: 10 } }] }), PLOT_CONFIG);
  const poles = res.poles;
  const xs = poles.map((p) => p.real_1_per_s);
  const ys = poles.map((p) => p.frequency_hz * Math.sign(p.imag_rad_per_s || 0));
  const slow = poles.filter((p) => p.frequency_hz < 200).map((p) => p.real_1_per_s);
  const lo = Math.min(...(slow.length ? slow : xs));
  const hi = Math.max(...xs.filter((x) => x >= lo), 0);
  const pad = 0.08 * (hi - lo || 1);
  Plotly.react($("plot-poles"), [{
    x: xs, y: poles.map((p) => p.imag_rad_per_s / (2 * Math.PI)), type: "scatter",
    mode: "markers", name: "poles",
    marker: { size: 9, symbol: "x", color: xs.map((x) => (x > 0 ? "#b42318" : "#1f6feb")) },
    customdata: poles.map((p) => [p.frequency_hz, p.damping_ratio]),
    hovertemplate: "Re = %{x:.4g} 1/s<br>Im/2π = %{y:.4g} Hz<br>|s|/2π = " +
      "%{customdata[0]:.4g} Hz, ζ = %{customdata[1]:.3g}<extra></extra>",
  }], layout(`loop poles at ${fmt(res.table_speed_mm_s)} mm/s (friction linearised)`,
             "real part [1/s]", "imaginary part / 2π [Hz]",
             { xaxis: { range: [lo - pad, hi + pad] }, uirevision: `poles-${ys.length}`,
               shapes: [{ type: "line", xref: "x", yref: "paper", x0: 0, x1: 0, y0: 0, y1: 1,
                          line: { color: "#888", width: 1 } }] }), PLOT_CONFIG);
  const d = res.least_damped_mode;
  const loops = res.loops.map((lp) => `${lp.loop}: phase margin ` +
    `${fmt(lp.phase_margin_deg, 3, "°")}, gain margin ${fmt(lp.gain_margin_db, 3, "dB")}`)
    .join(" · ");
  $("linear-facts").textContent =
    `Steady sliding at ${fmt(res.table_speed_mm_s)} mm/s is linearly ` +
    `${res.inside_band ? "UNSTABLE (inside the band)" : "stable"}; least-damped mode ` +
    `${fmt(d.frequency_hz, 3)} Hz, ζ = ${fmt(d.damping_ratio, 3)} · ${loops}`;
}

// ------------------------------------------------------------------ critical speed

async function critical() {
  if (state.critJob) return;
  const r = await api("POST", "/api/jobs", { kind: "critical", settings: collect() });
  if (r.status === 422) {
    showMessages(r.data);
    return;
  }
  if (r.status !== 202) {
    $("critical-result").textContent = r.data.error || `refused (${r.status})`;
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
      `creeping bands [mm/s]: ${c.bands_text}`;
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
  document.body.dataset.ready = "yes";
  if (Object.keys(first.data.errors || {}).length === 0) run();
}

window.addEventListener("DOMContentLoaded", start);
