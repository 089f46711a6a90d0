// The yarf queue page: polls the dashboard's JSON API, keeps one table row
// per job (updated in place, so inputs and images survive a refresh), and
// sends Cancel and priority changes. Job names and errors come from other
// users: they are only ever set with textContent.
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
  if (job.samples_done === 0 && job.state !== "RUNNING") return;
  const now = Date.now();
  const running = job.state === "RUNNING";
  // The submission time tells apart two jobs of one id (a server started afresh).
  let key = `${job.submitted_at}:${job.state}:${job.samples_done}`;
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

async function refresh() {
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
  refresh();
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

async function poll() {
  await refresh();
  setTimeout(poll, POLL_MS);
}

poll();
