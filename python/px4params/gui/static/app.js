// px4params gui: the device manifest in a browser. Everything on this page is built from the
// vehicle's parameters.json (its metadata) and its flat parameters (classic names,
// destructured names such as INA238_1C, instance masks such as INA238_INST); edits collect
// into a review and are written, in order, only when confirmed.
"use strict";

const S = {
  meta: { parameters: [] }, values: {}, staged: new Map(), health: [], messages: [],
  byName: new Map(), structured: [], classic: [], order: new Map(), notes: [], results: new Map(), limits: {},
};

const $ = (sel, root = document) => root.querySelector(sel);
const el = (tag, attrs = {}, ...children) => {
  const node = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "class") node.className = v;
    else if (k.startsWith("on")) node.addEventListener(k.slice(2), v);
    else if (v !== undefined && v !== null && v !== false) node.setAttribute(k, v === true ? "" : v);
  }
  for (const c of children.flat()) if (c !== null && c !== undefined) node.append(c.nodeType ? c : String(c));
  return node;
};

// -- the model -----------------------------------------------------------------------------

function index() {
  S.byName = new Map(S.meta.parameters.map((e) => [e.name, e]));
  S.structured = S.meta.parameters.filter((e) => e.type === "Custom");
  S.order = new Map();
  const destructured = new Set();
  for (const e of S.structured) {
    e._letters = new Map((e.flat || []).map((f) => [f.path, f.letter]));
    if (e.max_instances !== null) { S.order.set(e.name + "_INST", 0); destructured.add(e.name + "_INST"); }
    for (const f of e.flat || []) {
      for (let n = 0; n < (e.max_instances || 1); n++) {
        const name = flatName(e, n, f.path);
        destructured.add(name);
        if (/\._(tag|len)$/.test(f.path)) S.order.set(name, 1);
      }
    }
  }
  S.classic = S.meta.parameters.filter(
    (e) => (e.type === "Int32" || e.type === "Float") && !destructured.has(e.name));
}

function flatName(e, n, path) {
  const letter = e._letters.get(path);
  if (letter === undefined) return null;
  return e.max_instances === null ? `${e.name}_${letter}` : `${e.name}_${n}${letter}`;
}

const current = (name) => S.values[name];
const effective = (name) => (S.staged.has(name) ? S.staged.get(name).value : S.values[name]);

function defaultOf(name, field) {
  const entry = S.byName.get(name);
  if (entry && typeof entry.default === "number") return entry.default;
  return typeof field.default === "boolean" ? Number(field.default) : field.default;
}

function stage(name, value, label, unit) {
  if (name === null) return;
  if (current(name) === value) S.staged.delete(name);
  else S.staged.set(name, { name, value, label, unit: unit || "" });
  S.results.delete(name);
  updatePending();
}

function updatePending() {
  $("#pending").textContent = S.staged.size;
  $("#review-open").disabled = S.staged.size === 0;
}

// -- reading what the user typed -------------------------------------------------------------

function parseValue(text, kind, min, max) {
  const t = String(text).trim();
  let v;
  if (kind === "Float") {
    if (!/^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$/.test(t)) return { error: "not a number" };
    v = Number(t);
  } else {
    if (/^[+-]?0[xX][0-9a-fA-F]+$/.test(t)) v = (t.startsWith("-") ? -1 : 1) * parseInt(t.replace(/^[+-]/, ""), 16);
    else if (/^[+-]?\d+$/.test(t)) v = parseInt(t, 10);
    else return { error: "not an integer (decimal or 0x hex)" };
  }
  if (typeof min === "number" && v < min) return { error: `below the minimum ${min}` };
  if (typeof max === "number" && v > max) return { error: `above the maximum ${max}` };
  return { value: v };
}

function shown(v, decimals) {
  if (v === undefined || v === null) return "";
  if (typeof v === "number" && typeof decimals === "number") return v.toFixed(decimals);
  if (typeof v === "number" && !Number.isInteger(v)) return String(Number(v.toPrecision(7)));
  return String(v);
}

// -- structured instances ----------------------------------------------------------------------

function renderManifest() {
  const root = $("#manifest");
  root.replaceChildren();
  for (const e of S.structured) {
    const card = el("div", { class: "param", id: `param-${e.name}` },
      el("h3", {}, e.name, el("span", { class: "hint" }, `  ${e.dsdl_type}`)),
      el("p", { class: "desc" }, e.shortDesc || ""));
    const list = el("div", { class: "instances" });
    if (e.max_instances === null) {
      list.append(instanceCard(e, 0, "shared"));
    } else {
      const maskName = e.name + "_INST";
      const now = current(maskName) || 0;
      const want = effective(maskName) || 0;
      for (let n = 0; n < e.max_instances; n++) {
        const has = (now >> n) & 1, wants = (want >> n) & 1;
        if (has || wants) list.append(instanceCard(e, n, has && wants ? "" : wants ? "new" : "removed"));
      }
      const free = [...Array(e.max_instances).keys()].filter((n) => !((want >> n) & 1));
      const slot = el("div", { class: "slot" },
        el("span", {}, `${e.max_instances - free.length} of ${e.max_instances} instances`));
      if (free.length) {
        slot.append(el("button", {
          id: `add-${e.name}`,
          onclick: () => { stage(maskName, want | (1 << free[0]), `${e.name} instances`); renderManifest(); },
        }, `Add ${e.name}#${free[0]}`));
      }
      list.append(slot);
    }
    card.append(list);
    root.append(card);
  }
}

function instanceCard(e, n, status) {
  const title = e.max_instances === null ? e.name : `${e.name}#${n}`;
  const maskName = e.name + "_INST";
  const card = el("div", { class: `instance ${status}`, id: `instance-${e.name}-${n}`, "data-instance": title });
  const head = el("h4", {}, title);
  if (status === "removed") {
    head.append(el("button", {
      onclick: () => { stage(maskName, (effective(maskName) || 0) | (1 << n), `${e.name} instances`); renderManifest(); },
    }, "Keep"));
    card.append(head, el("p", { class: "hint" }, "removed when written"));
    return card;
  }
  if (e.max_instances !== null) {
    head.append(el("button", {
      class: "remove", title: `remove ${title}`,
      onclick: () => { stage(maskName, (effective(maskName) || 0) & ~(1 << n), `${e.name} instances`); renderManifest(); },
    }, "Remove"));
  }
  card.append(head);
  renderFields(card, e, n, e.fields, title);
  return card;
}

function renderFields(container, e, n, fields, title) {
  let skip = null;
  for (const f of fields) {
    if (skip && f.path.startsWith(skip)) continue;
    if (f.role === "padding" || f.role === "version") continue;
    if (f.role === "union_tag") {
      const union = f.path.slice(0, -"._tag".length);
      skip = union + ".";
      const name = flatName(e, n, f.path);
      const tag = valueOf(name, f);
      const select = el("select", { "data-name": name, "data-path": f.path, "aria-label": `${title} ${union}` },
        f.variants.map((v) => el("option", { value: v.tag, selected: v.tag === tag }, v.shortDesc || v.name)));
      select.addEventListener("change", () => {
        stage(name, Number(select.value), `${title}.${union} (variant)`);
        renderManifest();
      });
      container.append(fieldRow(f, name, select, union));
      const variant = f.variants.find((v) => v.tag === tag);
      if (variant) {
        const box = el("div", { class: "variant", "data-variant": variant.name });
        renderFields(box, e, n, variant.fields, title);
        container.append(box);
      }
    } else if (f.role === "length") {
      const array = f.path.slice(0, -"._len".length);
      skip = array + "[";
      const name = flatName(e, n, f.path);
      const length = valueOf(name, f);
      const items = el("div", { class: "array-items" });
      for (let i = 0; i < length; i++) {
        const item = el("div", { class: "item" });
        const element = f.element.map((x) => ({ ...x, path: x.path.replace(`${array}[]`, `${array}[${i}]`) }));
        renderFields(item, e, n, element, title);
        items.append(item);
      }
      const buttons = el("span", {},
        el("button", { disabled: length >= f.max, onclick: () => { stage(name, length + 1, `${title}.${array} (length)`); renderManifest(); } }, "Add"),
        el("button", { disabled: length <= 0, onclick: () => { stage(name, length - 1, `${title}.${array} (length)`); renderManifest(); } }, "Remove last"));
      container.append(fieldRow(f, name, el("span", {}, `${length} of ${f.max} `, buttons), array), items);
    } else {
      container.append(leafRow(e, n, f, title));
    }
  }
}

function valueOf(name, field) {
  const v = name === null ? undefined : effective(name);
  return v === undefined ? defaultOf(name, field) : v;
}

function fieldRow(f, name, control, label) {
  const row = el("div", { class: "field" + (S.staged.has(name) ? " changed" : ""), "data-field": f.path },
    el("span", { class: "label", title: f.shortDesc || "" }, label || f.name),
    el("span", { class: "control" }, control, f.unit ? el("span", { class: "unit" }, f.unit) : null));
  return row;
}

function leafRow(e, n, f, title) {
  const name = flatName(e, n, f.path);
  const kind = f.type.startsWith("float") ? "Float" : "Int32";
  const label = `${title}.${f.path}`;
  const value = valueOf(name, f);
  let control;
  if (f.type === "bool") {
    control = el("input", { type: "checkbox", class: "switch", "data-name": name, checked: Boolean(value), "aria-label": label });
    control.addEventListener("change", () => { stage(name, control.checked ? 1 : 0, label, f.unit); markRow(control, name); });
  } else if (f.values) {
    control = el("select", { "data-name": name, "aria-label": label },
      f.values.map((v) => el("option", { value: v.value, selected: v.value === value }, `${v.description} (${v.value})`)));
    control.addEventListener("change", () => { stage(name, Number(control.value), label, f.unit); markRow(control, name); });
  } else {
    control = el("input", {
      type: "text", inputmode: kind === "Float" ? "decimal" : "numeric", "data-name": name,
      value: shown(value, kind === "Float" ? f.decimalPlaces : undefined),
      "aria-label": label, title: `${f.min} .. ${f.max}${f.unit ? " " + f.unit : ""}`,
    });
    control.addEventListener("input", () => {
      const row = control.closest(".field");
      const parsed = parseValue(control.value, kind, f.min, f.max);
      row.querySelector(".error")?.remove();
      row.classList.toggle("invalid", Boolean(parsed.error));
      if (parsed.error) {
        S.staged.delete(name); // an invalid entry is never sent
        updatePending();
        row.append(el("span", { class: "error", role: "alert" }, `${control.value}: ${parsed.error}`));
        return;
      }
      stage(name, parsed.value, label, f.unit);
      markRow(control, name);
    });
  }
  return fieldRow(f, name, control, f.name);
}

function markRow(control, name) {
  control.closest(".field")?.classList.toggle("changed", S.staged.has(name));
}

// -- classic parameters, as QGC's editor lists them ------------------------------------------------

function renderClassic() {
  const root = $("#groups");
  root.replaceChildren();
  const query = $("#search").value.trim().toLowerCase();
  const modifiedOnly = $("#modified-only").checked;
  const groups = new Map();
  for (const e of S.classic) {
    if (!(e.name in S.values)) continue;
    const text = `${e.name} ${e.shortDesc || ""}`.toLowerCase();
    if (query && !text.includes(query)) continue;
    const modified = typeof e.default === "number" && effective(e.name) !== e.default;
    if (modifiedOnly && !modified) continue;
    if (!groups.has(e.group || "Miscellaneous")) groups.set(e.group || "Miscellaneous", []);
    groups.get(e.group || "Miscellaneous").push(e);
  }
  for (const [group, entries] of [...groups].sort()) {
    const body = el("tbody");
    for (const e of entries) body.append(classicRow(e));
    root.append(el("div", { class: "group" }, el("h2", {}, group),
      el("table", {}, el("thead", {}, el("tr", {}, ["Name", "Value", "Unit", "Default", "Description", ""].map((h) => el("th", {}, h)))), body)));
  }
  if (!groups.size) root.append(el("p", { class: "hint" }, "No parameter matches."));
}

function classicRow(e) {
  const value = effective(e.name);
  const modified = typeof e.default === "number" && value !== e.default;
  const row = el("tr", { class: (modified ? "modified" : "") + (S.staged.has(e.name) ? " changed" : ""), "data-param": e.name });
  const decimals = e.type === "Float" ? e.decimalPlaces : undefined;
  const input = el("input", { type: "text", value: shown(value, decimals), "data-name": e.name, "aria-label": e.name });
  const error = el("div", { class: "error" });
  input.addEventListener("input", () => {
    const parsed = parseValue(input.value, e.type, e.min, e.max);
    row.classList.toggle("invalid", Boolean(parsed.error));
    error.textContent = parsed.error ? `${input.value}: ${parsed.error}` : "";
    if (parsed.error) { S.staged.delete(e.name); updatePending(); return; }
    stage(e.name, parsed.value, e.name, e.units);
    row.classList.toggle("changed", S.staged.has(e.name));
  });
  const reset = el("button", {
    disabled: !modified, title: `reset ${e.name} to its default`,
    onclick: () => { stage(e.name, e.default, e.name, e.units); renderClassic(); },
  }, "Reset");
  row.append(
    el("td", { class: "name" }, e.name, e.rebootRequired ? el("span", { class: "reboot", title: "a change takes effect after a reboot" }, "reboot") : null),
    el("td", { class: "value" }, input, error),
    el("td", {}, e.units || ""),
    el("td", {}, shown(e.default)),
    el("td", { class: "hint" }, e.shortDesc || ""),
    el("td", {}, reset));
  return row;
}

// -- health --------------------------------------------------------------------------------

function renderHealth() {
  const body = $("#health-table tbody");
  body.replaceChildren(...S.health.map((h) => el("tr", { "data-instance": h.instance },
    el("td", {}, h.instance), el("td", {}, h.driver), el("td", {}, h.location),
    el("td", { class: `state-${h.state}` }, h.state), el("td", {}, h.reason))));
  $("#health-empty").hidden = S.health.length > 0;
  $("#messages").replaceChildren(...S.messages.slice(-30).map((m) => el("li", {}, m)));
  for (const card of document.querySelectorAll(".instance[data-instance]")) {
    const report = S.health.find((h) => h.instance === card.dataset.instance);
    const h4 = card.querySelector("h4");
    h4.querySelector(".badge")?.remove();
    if (report) h4.firstChild.after(el("span", { class: `badge ${report.state}` }, report.state));
  }
}

// -- review and write ------------------------------------------------------------------------------

function sortedChanges() {
  return [...S.staged.values()].sort((a, b) =>
    (S.order.get(a.name) ?? 2) - (S.order.get(b.name) ?? 2) || a.name.localeCompare(b.name));
}

function openReview() {
  const body = $("#review-table tbody");
  body.replaceChildren();
  for (const c of sortedChanges()) {
    const result = S.results.get(c.name);
    body.append(el("tr", { "data-name": c.name },
      el("td", {}, el("input", { type: "checkbox", checked: true, "aria-label": `write ${c.name}` })),
      el("td", {}, c.name, el("div", { class: "hint" }, c.label || "")),
      el("td", {}, current(c.name) === undefined ? "—" : shown(current(c.name))),
      el("td", {}, shown(c.value)),
      el("td", {}, c.unit || ""),
      el("td", { class: "result" }, result || "")));
  }
  $("#review-notes").textContent = S.notes.join(" ");
  const dialog = $("#review");
  if (!dialog.open) dialog.showModal();
}

async function writeSelected() {
  const rows = [...document.querySelectorAll("#review-table tbody tr")];
  const chosen = rows.filter((r) => r.querySelector("input").checked).map((r) => r.dataset.name);
  const changes = sortedChanges().filter((c) => chosen.includes(c.name));
  if (!changes.length) return;
  $("#review-write").disabled = true;
  // In parts of at most the server's limit of changes per request, in order.
  const part = S.limits.changes || changes.length;
  for (let i = 0; i < changes.length; i += part) {
    const response = await fetch("/api/write", {
      method: "POST", headers: { "content-type": "application/json" },
      body: JSON.stringify({ changes: changes.slice(i, i + part).map((c) => ({ name: c.name, value: c.value })) }),
    });
    const answer = await response.json();
    if (!response.ok) { $("#review-notes").textContent = answer.error; break; }
    S.values = answer.values;
    for (const r of answer.results) {
      const row = document.querySelector(`#review-table tr[data-name="${CSS.escape(r.name)}"] .result`);
      const text = r.ok ? `acknowledged: ${shown(r.value)}` : `refused: ${r.reason}`;
      if (row) { row.textContent = text; row.className = `result ${r.ok ? "result-ok" : "result-refused"}`; }
      S.results.set(r.name, text);
      S.staged.delete(r.name);
    }
  }
  $("#review-write").disabled = false;
  updatePending();
  renderAll();
}

async function loadFile(file) {
  const text = await file.text();
  const response = await fetch("/api/review", {
    method: "POST", headers: { "content-type": "application/json" },
    body: JSON.stringify({ filename: file.name, text }),
  });
  const answer = await response.json();
  if (!response.ok) { S.notes = [answer.error]; openReview(); return; }
  for (const c of answer.changes) stage(c.name, c.new, `from ${file.name}`, S.byName.get(c.name)?.units);
  S.notes = [`${file.name}: ${answer.changes.length} changes.`, ...answer.notes];
  renderAll();
  openReview();
}

// -- live values -------------------------------------------------------------------------------

function connect() {
  const ws = new WebSocket(`${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/ws`);
  ws.onmessage = (event) => {
    const msg = JSON.parse(event.data);
    if (msg.kind === "value") S.values[msg.name] = msg.value;
    else if (msg.kind === "values") S.values = msg.values;
    else if (msg.kind === "status") {
      S.messages.push(msg.text);
      if (msg.health) {
        S.health = S.health.filter((h) => h.instance !== msg.health.instance).concat([msg.health]);
      }
    }
    scheduleRender();
  };
  ws.onclose = () => setTimeout(connect, 2000);
}

let pending = false;
function scheduleRender() {
  if (pending) return;
  pending = true;
  requestAnimationFrame(() => {
    pending = false;
    const active = document.activeElement;
    if (active && active.matches("input, select") && !$("#review").open) return renderHealth();
    renderAll();
  });
}

function renderAll() {
  renderManifest();
  renderClassic();
  renderHealth();
}

async function start() {
  for (const tab of document.querySelectorAll(".tab")) {
    tab.addEventListener("click", () => {
      document.querySelectorAll(".tab, .panel").forEach((x) => x.classList.remove("active"));
      tab.classList.add("active");
      $(`#${tab.dataset.tab}`).classList.add("active");
    });
  }
  $("#search").addEventListener("input", renderClassic);
  $("#modified-only").addEventListener("change", renderClassic);
  $("#review-open").addEventListener("click", openReview);
  $("#review-close").addEventListener("click", () => $("#review").close());
  $("#review-write").addEventListener("click", writeSelected);
  $("#review-discard").addEventListener("click", () => { S.staged.clear(); updatePending(); $("#review").close(); renderAll(); });
  $("#review-all").addEventListener("change", (ev) => {
    document.querySelectorAll("#review-table tbody input").forEach((i) => { i.checked = ev.target.checked; });
  });
  $("#load").addEventListener("change", (ev) => { if (ev.target.files[0]) loadFile(ev.target.files[0]); ev.target.value = ""; });
  const response = await fetch("/api/state");
  const state = await response.json();
  S.meta = state.metadata; S.values = state.values; S.health = state.health; S.messages = state.messages;
  S.limits = state.limits || {};
  $("#source").textContent = `${state.mode === "store" ? "offline store" : "vehicle"}: ${state.source}`;
  index();
  renderAll();
  updatePending();
  document.body.dataset.ready = "true";
  connect();
}

start();
