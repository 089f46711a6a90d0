// The yarf queue page: polls the dashboard's JSON API, keeps one table row
// per job (updated in place, so inputs and images survive a refresh), sends
// Cancel, priority changes and uploaded scene files, and shows one job's
// page at #/jobs/<id>. Job names, errors, parameters and log lines come from
// other users: they are only ever set with textContent.
"use strict";

const POLL_MS = 1000;
// A running job's preview is fetched again after a new sample pass, and at
// least this often while a long pass runs.
const PREVIEW_MS = 3000;
const FINAL_STATES = new Set(["SUCCEEDED", "FAILED", "CANCELLED"]);

// Job id → its row and the elements updateRow changes.
const rows = new Map();

function jobUrl(jobId, action) {
  return `/api/jobs/${encodeURIComponent(jobId)}/${action}`;
}

function jobPageHash(jobId) {
  return `#/jobs/${encodeURIComponent(jobId)}`;
}

// Whether a job has an image to show: once a pass is done, or while it runs.
function hasImage(job) {
  return job.samples_done > 0 || job.state === "RUNNING";
}

// The key of a job's image: the submission time tells apart two jobs of one
// id (a server started afresh), the state and samples its versions.
function imageKey(job) {
  return `${job.submitted_at}:${job.state}:${job.samples_done}`;
}

// Calls the API; resolves to the reply's JSON, rejects with its error message.
async function api(path, body) {
  const options = body === undefined ? {} : {
    method: "POST",
    headers: {"Content-Type": "application/json"},
    body: JSON.stringify(body),
  };
  const reply = await fetch(path, options);
  const data = await reply.json().catch(() => ({}));
  if (!reply.ok) {
    throw new Error(data.error || `${reply.status} ${reply.statusText}`);
  }
  return data;
}

// How long the error of a Cancel or priority change stays on the page.
const ACTION_ERROR_MS = 10000;
let actionErrorTimer = 0;

function showText(id, text) {
  const element = document.getElementById(id);
  element.textContent = text;
  element.hidden = !text;
}

// A failed Cancel or priority change; the list's own refreshes leave it be.
function showActionError(text) {
  showText("action-error", text);
  clearTimeout(actionErrorTimer);
  actionErrorTimer = setTimeout(() => showText("action-error", ""), ACTION_ERROR_MS);
}

// 42 s, 3 min 07 s, 2 h 05 min.
function formatDuration(seconds) {
  const whole = Math.round(seconds);
  if (whole < 60) return `${whole} s`;
  if (whole < 3600) return `${Math.floor(whole / 60)} min ${String(whole % 60).padStart(2, "0")} s`;
  const minutes = String(Math.floor((whole % 3600) / 60)).padStart(2, "0");
  return `${Math.floor(whole / 3600)} h ${minutes} min`;
}

function createRow(jobId) {
  const row = document.getElementById("job-row").content.firstElementChild.cloneNode(true);
  row.dataset.jobId = jobId;
  const fields = {};
  for (const cell of row.querySelectorAll("[data-field]")) fields[cell.dataset.field] = cell;
  const entry = {
    row,
    fields,
    img: row.querySelector(".preview img"),
    link: row.querySelector(".preview a"),
    progress: row.querySelector("progress"),
    cancel: row.querySelector("button.cancel"),
    priorityForm: row.querySelector("form.set-priority"),
    previewKey: "",
    previewAt: 0,
  };
  // Invisible but laid out until an image arrives (a lazy image loads when on screen).
  entry.img.addEventListener("error", () => entry.img.classList.add("empty"));
  entry.img.addEventListener("load", () => entry.img.classList.remove("empty"));
  entry.cancel.addEventListener("click", () => cancelJob(entry, jobId));
  entry.priorityForm.addEventListener("submit", (event) => {
    event.preventDefault();
    setPriority(entry, jobId, event.target);
  });
  return entry;
}

function updateRow(entry, job) {
  const {fields} = entry;
  fields.job_id.textContent = job.job_id;
  fields.job_id.href = jobPageHash(job.job_id);
  if (job.submitted_at) {
    fields.job_id.title = `submitted ${new Date(job.submitted_at * 1000).toLocaleString()}`;
  }
  fields.name.textContent = job.name;
  fields.owner.textContent = job.owner || "–";
  fields.state.textContent = job.state;
  entry.row.dataset.state = job.state;
  fields.error.textContent = job.error;
  fields.priority.textContent = job.priority ? String(job.priority) : "–";
  entry.progress.value = job.percent;
  entry.progress.textContent = `${Math.round(job.percent)}%`;
  fields.samples.textContent = `${job.samples_done}/${job.samples_total} spp`;
  fields.eta.textContent =
    job.state === "RUNNING" && job.eta_seconds > 0 ? formatDuration(job.eta_seconds) : "";
  // A finished job can be neither stopped nor moved in the queue.
  const finished = FINAL_STATES.has(job.state);
  entry.cancel.disabled = finished;
  for (const control of entry.priorityForm.elements) control.disabled = finished;
  updatePreview(entry, job);
}

// Loads the job's image when there is a new one: after each sample pass,
// every PREVIEW_MS while it runs, and once more when it ends.
function updatePreview(entry, job) {
  if (!hasImage(job)) return;
  const now = Date.now();
  const running = job.state === "RUNNING";
  let key = imageKey(job);
  if (running && now - entry.previewAt >= PREVIEW_MS) key += `:${now}`;
  if (key === entry.previewKey) return;
  if (running && entry.img.src && !entry.img.complete) return;  // the last one is still loading
  entry.previewKey = key;
  entry.previewAt = now;
  const url = `${jobUrl(job.job_id, "preview.png")}?v=${encodeURIComponent(key)}`;
  entry.img.src = url;
  entry.img.alt = `Image of ${job.job_id}`;
  entry.link.href = url;
}

function render(jobs) {
  const tbody = document.querySelector("#jobs tbody");
  const seen = new Set();
  jobs.forEach((job, index) => {
    let entry = rows.get(job.job_id);
    if (!entry) {
      entry = createRow(job.job_id);
      rows.set(job.job_id, entry);
    }
    updateRow(entry, job);
    // Keep the server's order (newest first) without rebuilding rows.
    if (tbody.children[index] !== entry.row) {
      tbody.insertBefore(entry.row, tbody.children[index] || null);
    }
    seen.add(job.job_id);
  });
  for (const [jobId, entry] of rows) {
    if (!seen.has(jobId)) {
      entry.row.remove();
      rows.delete(jobId);
    }
  }
  document.getElementById("empty").hidden = jobs.length > 0;
  const counts = {};
  for (const job of jobs) counts[job.state] = (counts[job.state] || 0) + 1;
  document.getElementById("summary").textContent = Object.entries(counts)
    .map(([state, count]) => `${count} ${state.toLowerCase()}`)
    .join(" · ");
}

async function refreshQueue() {
  try {
    const data = await api("/api/jobs");
    render(data.jobs);
    showText("list-error", "");
  } catch (error) {
    showText("list-error", `Cannot list the jobs: ${error.message}`);
  }
}

async function cancelJob(entry, jobId) {
  entry.cancel.disabled = true;
  try {
    updateRow(entry, await api(jobUrl(jobId, "cancel"), {}));
  } catch (error) {
    showActionError(`Cannot cancel ${jobId}: ${error.message}`);
  }
  refreshQueue();
}

async function setPriority(entry, jobId, form) {
  const priority = Number(form.elements.priority.value);
  try {
    updateRow(entry, await api(jobUrl(jobId, "priority"), {priority}));
    form.reset();
  } catch (error) {
    showActionError(`Cannot change the priority of ${jobId}: ${error.message}`);
  }
}

// Uploads the chosen scene file with its options; the server loads it as
// `yarf submit` would and answers the new job.
async function uploadScene(form) {
  const file = form.elements.scene.files[0];
  if (!file) return;
  const params = new URLSearchParams({file: file.name});
  if (form.elements.spp.value) params.set("spp", form.elements.spp.value);
  if (form.elements.transport.value) params.set("transport", form.elements.transport.value);
  const button = form.querySelector("button[type=submit]");
  const status = document.querySelector("#upload-status a");
  button.disabled = true;
  status.textContent = `Sending ${file.name}…`;
  status.removeAttribute("href");
  try {
    const reply = await fetch(`/api/jobs?${params}`, {
      method: "POST",
      headers: {"Content-Type": "application/octet-stream"},
      body: file,
    });
    const data = await reply.json().catch(() => ({}));
    if (!reply.ok) throw new Error(data.error || `${reply.status} ${reply.statusText}`);
    // What the importer ignored or approximated, in the link's tooltip.
    const warnings = data.warnings || [];
    const noted = warnings.length === 1 ? "1 import warning" : `${warnings.length} import warnings`;
    status.textContent = `Submitted ${data.job_id}${warnings.length ? ` (${noted})` : ""}`;
    status.title = warnings.join("\n");
    status.href = jobPageHash(data.job_id);
    showText("upload-error", "");
    form.reset();
    refreshQueue();
  } catch (error) {
    status.textContent = "";
    showText("upload-error", `Cannot submit ${file.name}: ${error.message}`);
  } finally {
    button.disabled = false;
  }
}

// The job page.

// What the page shows now: the job id of #/jobs/<id>, or null for the queue.
function routeJobId() {
  const match = /^#\/jobs\/([^/]+)$/.exec(location.hash);
  if (!match) return null;
  try {
    return decodeURIComponent(match[1]);
  } catch {
    return null;
  }
}

// The job page's state: which job it shows and what it has loaded.
const jobView = {jobId: null, imageKey: "", aovKey: "", endedLoads: 0};

function cell(tag, text) {
  const element = document.createElement(tag);
  element.textContent = text;
  return element;
}

// Fills a table's body with [label, value] rows; a value is text or an element.
function fillTable(id, rows) {
  document.querySelector(`#${id} tbody`).replaceChildren(...rows.map(([label, value]) => {
    const row = document.createElement("tr");
    const data = document.createElement("td");
    if (value instanceof Node) data.append(value);
    else data.textContent = value;
    row.append(cell("th", label), data);
    return row;
  }));
}

function formatNumber(value) {
  return Number.isInteger(value) ? String(value) : String(Number(value.toPrecision(4)));
}

function formatValue(value) {
  if (Array.isArray(value)) return `(${value.map(formatNumber).join(", ")})`;
  if (value && value.matrix) return "a 4×4 matrix";
  if (value && typeof value === "object") return `→ ${value.reference}`;
  if (typeof value === "number") return formatNumber(value);
  return String(value);
}

// "path (max_depth 6) at host:port", or the default's name when unset.
function formatComponent(spec, unset) {
  if (!spec) return unset;
  const properties = Object.entries(spec.properties)
    .map(([key, value]) => `${key} ${formatValue(value)}`);
  let text = spec.class_name || unset;
  if (properties.length) text += ` (${properties.join(", ")})`;
  if (spec.address) text += ` at ${spec.address}`;
  return text;
}

const NOT_KEPT = "not kept (the job ended before this yarfd started)";

function optionRows(options) {
  if (!options) return [["Options", NOT_KEPT]];
  const crop = options.crop;
  return [
    ["Samples per pixel", String(options.spp)],
    ["Seed", String(options.seed)],
    ["Transport", formatComponent(options.transport, "the scene's")],
    ["Integrator", formatComponent(options.integrator, "the scene's")],
    ["Sampler", formatComponent(options.sampler, "the scene's")],
    ["Crop window", crop ? `x ${crop[0]}–${crop[1]}, y ${crop[2]}–${crop[3]}` : "whole film"],
    ["AOVs", options.aovs.length ? options.aovs.join(", ") : "none"],
    ["Threads", options.threads ? String(options.threads) : "the server's"],
  ];
}

function sceneRows(scene) {
  if (!scene) return [["Scene", NOT_KEPT]];
  return [
    ["Film", `${scene.width} × ${scene.height}`],
    ["Camera", scene.camera || "–"],
    ["Shapes", String(scene.shapes)],
    ["Instances", String(scene.instances)],
    ["Materials", String(scene.materials)],
    ["Lights", String(scene.lights)],
    ["Textures", String(scene.textures)],
    ["Media", String(scene.media)],
  ];
}

function statusRows(job) {
  const state = cell("span", job.state);
  state.className = "state";
  const rows = [
    ["Job", job.job_id],
    ["State", state],
    ["Owner", job.owner || "–"],
    ["Priority", job.priority ? String(job.priority) : "–"],
    ["Elapsed", formatDuration(job.elapsed_seconds)],
  ];
  if (job.state === "RUNNING" && job.eta_seconds > 0) rows.push(["ETA", formatDuration(job.eta_seconds)]);
  rows.push(["Attempts", String(job.attempts)]);
  if (job.submitted_at) {
    rows.push(["Submitted", new Date(job.submitted_at * 1000).toLocaleString()]);
  }
  return rows;
}

function renderJobImage(job) {
  const image = document.getElementById("job-image");
  const downloads = document.getElementById("job-downloads");
  downloads.hidden = !hasImage(job);
  if (!hasImage(job)) return;
  let key = imageKey(job);
  if (job.state === "RUNNING") key += `:${Math.floor(Date.now() / PREVIEW_MS)}`;
  if (key === jobView.imageKey) return;
  if (job.state === "RUNNING" && image.src && !image.complete) return;
  jobView.imageKey = key;
  image.src = `${jobUrl(job.job_id, "preview.png")}?v=${encodeURIComponent(key)}`;
  image.alt = `Image of ${job.job_id}`;
  document.getElementById("download-exr").href = jobUrl(job.job_id, "image.exr");
  document.getElementById("download-png").href = jobUrl(job.job_id, "image.png");
}

// An ended job's AOVs, each as a captioned thumbnail; made once per job.
function renderAovs(job, names) {
  const section = document.getElementById("job-aov-section");
  const ready = FINAL_STATES.has(job.state) && job.samples_done > 0 && names.length > 0;
  section.hidden = !ready;
  const key = `${job.submitted_at}:${names.join(",")}`;
  if (!ready || key === jobView.aovKey) return;
  jobView.aovKey = key;
  document.getElementById("job-aovs").replaceChildren(...names.map((name) => {
    const figure = document.createElement("figure");
    figure.className = "aov";
    figure.dataset.aov = name;
    const image = document.createElement("img");
    image.src = `${jobUrl(job.job_id, `aov/${encodeURIComponent(name)}.png`)}?v=${job.submitted_at}`;
    image.alt = `${name} of ${job.job_id}`;
    figure.append(image, cell("figcaption", name));
    return figure;
  }));
}

function renderJob(data) {
  const {job} = data;
  document.getElementById("job-title").textContent = job.name || job.job_id;
  document.getElementById("job-view").dataset.state = job.state;
  const progress = document.getElementById("job-progress");
  progress.value = job.percent;
  progress.textContent = `${Math.round(job.percent)}%`;
  document.getElementById("job-samples").textContent =
    `${job.samples_done}/${job.samples_total} spp`;
  fillTable("job-status", statusRows(job));
  fillTable("job-options", optionRows(data.options));
  fillTable("job-scene", sceneRows(data.scene));
  document.getElementById("job-error").textContent = data.error;
  document.getElementById("job-error-section").hidden = !data.error;
  document.getElementById("job-log").replaceChildren(...data.log.map((line) => cell("li", line)));
  renderJobImage(job);
  renderAovs(job, data.aovs);
  jobView.endedLoads = FINAL_STATES.has(job.state) ? jobView.endedLoads + 1 : 0;
}

async function refreshJob(jobId) {
  // An ended job no longer changes: its page is loaded once more after it
  // ended (for a log line written just after its state), then left be.
  if (jobView.endedLoads >= 2) return;
  try {
    const data = await api(`/api/jobs/${encodeURIComponent(jobId)}`);
    if (jobView.jobId !== jobId) return;  // the page moved on meanwhile
    renderJob(data);
    showText("job-load-error", "");
  } catch (error) {
    if (jobView.jobId === jobId) showText("job-load-error", `Cannot load ${jobId}: ${error.message}`);
  }
}

// Shows the queue or a job's page, as the address's #fragment says.
function route() {
  const jobId = routeJobId();
  document.getElementById("queue-view").hidden = jobId !== null;
  document.getElementById("job-view").hidden = jobId === null;
  document.title = jobId === null ? "yarf queue" : `${jobId} · yarf`;
  if (jobId !== jobView.jobId) {
    Object.assign(jobView, {jobId, imageKey: "", aovKey: "", endedLoads: 0});
    if (jobId !== null) {
      document.getElementById("job-title").textContent = jobId;
      document.getElementById("job-image").removeAttribute("src");
      document.getElementById("job-image").classList.add("empty");
      document.getElementById("job-aovs").replaceChildren();
      document.getElementById("job-aov-section").hidden = true;
      document.getElementById("job-downloads").hidden = true;
    }
  }
  return refresh();
}

function refresh() {
  return jobView.jobId === null ? refreshQueue() : refreshJob(jobView.jobId);
}

async function poll() {
  await refresh();
  setTimeout(poll, POLL_MS);
}

const jobImage = document.getElementById("job-image");
jobImage.addEventListener("error", () => jobImage.classList.add("empty"));
jobImage.addEventListener("load", () => jobImage.classList.remove("empty"));
document.getElementById("upload").addEventListener("submit", (event) => {
  event.preventDefault();
  uploadScene(event.target);
});
window.addEventListener("hashchange", route);
route().then(() => setTimeout(poll, POLL_MS));
