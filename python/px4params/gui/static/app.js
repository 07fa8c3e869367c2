// px4params gui: the device manifest in a browser. Everything on this page is built from the
// vehicle's parameters.json (its metadata), its flat parameters (classic names, destructured
// names such as INA238_1C, instance masks such as INA238_INST) and the driver declarations
// (/api/manifest: the picker, and each device's location and what stops it from starting).
// Edits collect into a review, read in words, and are written, in order, only when confirmed.
"use strict";

const S = {
  meta: { parameters: [] }, values: {}, staged: new Map(), health: [], messages: [], mode: "",
  byName: new Map(), structured: [], classic: [], order: new Map(), notes: [], results: new Map(), limits: {},
  drivers: new Map(), picker: [], devices: new Map(), devicesNow: new Map(),
  instanceNames: new Map(), // parameter -> its instances' names, by number (the server's)
  instanceOf: new Map(),    // an instance's name -> {e, n}
  invalid: new Map(), // name -> {text, error}: a wrong entry stays until corrected or discarded
  memory: {},         // union tag name -> {variant tag -> {flat name -> value}}, for the session
};
const MEMORY_KEY = "px4params.variants";
const BOARD_KEY = "px4params.board"; // the flight controller, chosen once per browser

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

// -- numbers as the vehicle stores them ------------------------------------------------------

// float16 as the DroneCAN rules convert to it: nearest, ties away from zero, finite values
// clamped to +-65504.
function f16round(x) {
  if (!Number.isFinite(x) || x === 0) return x;
  const a = Math.abs(x);
  let e = Math.floor(Math.log2(a));
  if (2 ** e > a) e -= 1; else if (2 ** (e + 1) <= a) e += 1;
  const quantum = 2 ** (Math.max(e, -14) - 10);
  const r = Math.min(Math.floor(a / quantum + 0.5) * quantum, 65504);
  return Math.sign(x) * r;
}

// How a value of this kind is stored: "float16", "Float"/"float32" (float32), else as is.
function storedAs(v, kind) {
  if (typeof v !== "number") return v;
  if (kind === "float16") return f16round(v);
  if (kind === "Float" || kind === "float32") return Math.fround(v);
  return v;
}
const sameStored = (a, b, kind) => a !== undefined && b !== undefined && storedAs(a, kind) === storedAs(b, kind);

// -- the model -----------------------------------------------------------------------------

function index() {
  S.byName = new Map(S.meta.parameters.map((e) => [e.name, e]));
  S.structured = S.meta.parameters.filter((e) => e.type === "Custom");
  S.order = new Map();
  S.instanceNames = new Map();
  S.instanceOf = new Map();
  const destructured = new Set();
  for (const e of S.structured) {
    e._letters = new Map((e.flat || []).map((f) => [f.path, f.letter]));
    if (e.max_instances !== null) {
      S.order.set(e.name + "_INST", 0); destructured.add(e.name + "_INST");
      const names = (S.drivers.get(e.name) || {}).instances || [];
      S.instanceNames.set(e.name, names);
      names.forEach((name, n) => S.instanceOf.set(name, { e, n }));
    }
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
const maskOf = (e, values) => (values ? values[e.name + "_INST"] : effective(e.name + "_INST")) || 0;
// An instance's name as the server gives it (/api/manifest: each picker entry's `instances`,
// by number): the page composes no name. A shared parameter's is its own.
const titleOf = (e, n) => (e.max_instances === null ? e.name : S.instanceNames.get(e.name)[n]);

function defaultOf(name, field) {
  const entry = S.byName.get(name);
  if (entry && typeof entry.default === "number") return entry.default;
  return typeof field.default === "boolean" ? Number(field.default) : field.default;
}

// Stages a change. ``info`` says what it is for the review: {title, field, e, n, kind, unit,
// force}; ``force`` keeps it staged even when the vehicle holds the same value (the fields of a
// variant being switched to: switching resets them on the vehicle).
function stage(name, value, info = {}) {
  if (name === null) return;
  S.invalid.delete(name);
  if (!info.force && sameStored(current(name), value, info.kind)) S.staged.delete(name);
  else S.staged.set(name, { name, value, ...info });
  S.results.delete(name);
  updatePending();
  scheduleCheck();
}

function unstageInstance(e, n) {
  for (const f of e.flat || []) {
    const name = flatName(e, n, f.path);
    S.staged.delete(name);
    S.invalid.delete(name);
  }
}

function updatePending() {
  $("#pending").textContent = S.staged.size ? reviewItems().length : 0; // review lines, not names
  $("#review-open").disabled = S.staged.size === 0;
}

// -- the driver declarations: devices and the picker ----------------------------------------------

let checkTimer = null;
function scheduleCheck() {
  clearTimeout(checkTimer);
  checkTimer = setTimeout(refreshDevices, 50);
}

function effectiveValues() {
  const values = { ...S.values };
  for (const [name, c] of S.staged) values[name] = c.value;
  return values;
}

async function check(all) {
  // numbers only: a non-finite float arrives as "nan"/"inf" and places no device
  const values = Object.fromEntries(Object.entries(all).filter(([, v]) => typeof v === "number"));
  const response = await fetch("/api/manifest", {
    method: "POST", headers: { "content-type": "application/json" },
    body: JSON.stringify({ values, board: $("#board").value || null }),
  });
  const answer = await response.json();
  return new Map((answer.devices || []).map((d) => [d.instance, d]));
}

async function refreshDevices() {
  const [staged, now] = await Promise.all([check(effectiveValues()), check(S.values)]);
  S.devices = staged;
  S.devicesNow = now;
  renderHealth(); // the places in the health table, and every card's status
}

// -- reading what the user typed -------------------------------------------------------------

function parseValue(text, kind, min, max, hex) {
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
  if (typeof min === "number" && v < min) return { error: `below the minimum ${numberText(min, hex)}` };
  if (typeof max === "number" && v > max) return { error: `above the maximum ${numberText(max, hex)}` };
  return { value: v };
}

function shown(v, decimals) {
  if (v === undefined || v === null) return "";
  if (typeof v === "number" && typeof decimals === "number") return v.toFixed(decimals);
  if (typeof v === "number" && !Number.isInteger(v)) return String(Number(v.toPrecision(7)));
  return String(v);
}

const numberText = (v, hex) => (hex && typeof v === "number" ? "0x" + v.toString(16).toUpperCase().padStart(2, "0") : shown(v));

// A leaf's value in words: its enum name, hex where the type says so, on/off for a switch.
function valueText(f, v) {
  if (v === undefined || v === null) return "—";
  if (f && f.type === "bool") return v ? "on" : "off";
  const named = f && f.values ? f.values.find((x) => x.value === v) : null;
  if (named) return named.description;
  const hex = f && f.format === "hex";
  const float = typeof v === "number" && f && f.type && f.type.startsWith("float");
  const text = float ? shown(v, f.decimalPlaces) : numberText(v, hex); // as the form shows it
  return f && f.unit ? `${text} ${f.unit}` : text;
}

const labelOf = (f) => f.shortDesc || f.name;

function rangeText(f) {
  if (f.values || f.type === "bool" || typeof f.min !== "number" || typeof f.max !== "number") return null;
  const hex = f.format === "hex";
  return `${numberText(f.min, hex)} to ${numberText(f.max, hex)}${f.unit || f.units ? " " + (f.unit || f.units) : ""}`;
}

// -- the vehicle's devices ---------------------------------------------------------------------

function pickerEntry(e) { return S.drivers.get(e.name); }

function renderManifest() {
  const root = $("#devices");
  root.replaceChildren();
  let count = 0;
  // in start order, as the drivers' `auto` lines run (and PX4's `status` lists them)
  const started = (e) => (pickerEntry(e) || {}).order ?? Infinity;
  for (const e of [...S.structured].sort((a, b) => started(a) - started(b))) {
    if (e.max_instances === null) continue;
    const now = maskOf(e, S.values), want = maskOf(e);
    for (let n = 0; n < e.max_instances; n++) {
      const has = (now >> n) & 1, wants = (want >> n) & 1;
      if (has || wants) { root.append(instanceCard(e, n, has && wants ? "" : wants ? "new" : "removed")); count++; }
    }
  }
  $("#devices-empty").hidden = count > 0;
  const shared = $("#shared");
  shared.replaceChildren();
  for (const e of S.structured.filter((x) => x.max_instances === null)) {
    shared.append(instanceCard(e, 0, "shared"));
  }
  $("#shared-section").hidden = shared.children.length === 0;
  renderPicker();
  renderDeviceStatus();
}

function instanceCard(e, n, status) {
  const title = titleOf(e, n);
  const driver = pickerEntry(e);
  const card = el("article", { class: `instance ${status}`, id: `instance-${e.name}-${n}`, "data-instance": title });
  const head = el("h3", {}, el("span", { class: "title" }, title),
    el("span", { class: "kind" }, driver && driver.kind ? driver.kind : e.shortDesc || ""));
  const buttons = el("span", { class: "card-buttons" });
  head.append(buttons);
  card.append(head, el("div", { class: "card-status" }));
  if (status === "removed") {
    buttons.append(el("button", { class: "keep", onclick: () => { setMask(e, maskOf(e) | (1 << n)); renderManifest(); } }, "Keep"));
    card.append(el("p", { class: "hint" }, "removed when written"));
    return card;
  }
  if (e.max_instances !== null) {
    buttons.append(el("button", {
      class: "remove", title: `remove ${title}`,
      onclick: () => { setMask(e, maskOf(e) & ~(1 << n)); renderManifest(); },
    }, "Remove"));
  }
  const form = el("div", { class: "fields" });
  renderFields(form, e, n, e.fields, title);
  card.append(form);
  return card;
}

// The badge, location and what blocks arming of every card, from the last check and health.
function renderDeviceStatus() {
  for (const card of document.querySelectorAll(".instance[data-instance]")) {
    const instance = card.dataset.instance;
    const removed = card.classList.contains("removed");
    const device = (removed ? S.devicesNow : S.devices).get(instance);
    const report = removed ? null : visibleHealth().find((h) => h.instance === instance);
    const box = card.querySelector(".card-status");
    if (!box) continue;
    const blocks = [];
    if (device) for (const p of device.problems) blocks.push(`cannot start: ${p}`);
    if (report && report.state !== "nominal") blocks.push(`${report.state}: ${report.reason || "no reason given"}`);
    const title = card.querySelector("h3 .title");
    card.querySelector("h3 .badge")?.remove();
    if (report) title.after(el("span", { class: `badge ${report.state}` }, report.state));
    box.replaceChildren(
      el("div", { class: "location" }, device ? device.location : ""),
      blocks.length
        ? el("ul", { class: "blocks" }, el("li", { class: "blocks-head" }, "Blocks arming:"), blocks.map((b) => el("li", {}, b)))
        : el("div", { class: "ready hint" }, removed ? "" : report ? "nothing blocks arming" : "no health report yet"));
  }
}

function setMask(e, want) {
  const maskName = e.name + "_INST";
  for (let n = 0; n < e.max_instances; n++) if (!((want >> n) & 1)) unstageInstance(e, n); // its edits go too
  stage(maskName, want, { title: `${e.name} instances`, e });
}

// A new instance, staged from the driver declaration's defaults: its bus kind, bus 1 and, on
// I2C, its default address; every other field its DSDL default.
function addInstance(e) {
  const want = maskOf(e);
  const n = [...Array(e.max_instances).keys()].find((k) => !((want >> k) & 1));
  if (n === undefined) return;
  setMask(e, want | (1 << n));
  const title = titleOf(e, n);
  const start = (pickerEntry(e) || {}).start || {};
  let skip = null;
  for (const f of e.fields) {
    if (skip && f.path.startsWith(skip)) continue;
    if (f.role === "union_tag") {
      const union = f.path.slice(0, -"._tag".length);
      skip = union + ".";
      const variant = (union === "bus" && f.variants.find((v) => v.name === start.bus)) || f.variants.find((v) => v.tag === f.default) || f.variants[0];
      const name = flatName(e, n, f.path);
      stage(name, variant.tag, { title, field: f, e, n, force: true, union, tag: true });
      stageVariant(e, n, f, variant, startValues(e, variant), title);
    } else if (f.role === "value") {
      stage(flatName(e, n, f.path), roundFor(f, f.default), { title, field: f, e, n, kind: f.type, force: true });
    }
  }
  return n;
}

const roundFor = (f, v) => (typeof v === "boolean" ? Number(v) : f.type === "float16" ? f16round(v) : v);
const variantLeaves = (variant) => variant.fields.filter((f) => f.role === "value");

function startValues(e, variant) {
  const start = ((pickerEntry(e) || {}).start || {}).variants || {};
  const overrides = start[variant.name] || {};
  const out = {};
  for (const f of variantLeaves(variant)) out[f.name] = f.name in overrides ? overrides[f.name] : roundFor(f, f.default);
  return out;
}

function stageVariant(e, n, tagField, variant, values, title) {
  const tagName = flatName(e, n, tagField.path);
  for (const f of variantLeaves(variant)) {
    stage(flatName(e, n, f.path), values[f.name], { title, field: f, e, n, kind: f.type, force: S.staged.has(tagName), variantOf: tagName });
  }
}

function loadMemory() {
  try { S.memory = JSON.parse(sessionStorage.getItem(MEMORY_KEY) || "{}"); } catch { S.memory = {}; }
}
function saveMemory() { sessionStorage.setItem(MEMORY_KEY, JSON.stringify(S.memory)); }

// Switching a union: the variant left is remembered, the one chosen comes back with its last
// values this session, or from the driver's defaults when never seen; never from zeros.
function switchVariant(e, n, f, tag, title) {
  const tagName = flatName(e, n, f.path);
  const before = valueOf(tagName, f);
  const memory = (S.memory[tagName] = S.memory[tagName] || {});
  const left = f.variants.find((v) => v.tag === before);
  if (left) {
    memory[left.tag] = Object.fromEntries(variantLeaves(left).map((x) => [x.name, valueOf(flatName(e, n, x.path), x)]));
  }
  for (const v of f.variants) for (const x of variantLeaves(v)) { S.staged.delete(flatName(e, n, x.path)); S.invalid.delete(flatName(e, n, x.path)); }
  stage(tagName, tag, { title, field: f, e, n, union: f.path.slice(0, -"._tag".length), tag: true });
  const variant = f.variants.find((v) => v.tag === tag);
  stageVariant(e, n, f, variant, { ...startValues(e, variant), ...(memory[tag] || {}) }, title);
  saveMemory();
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
      const select = el("select", { "data-name": name, "data-path": f.path, "aria-label": `${title} ${labelOf(f)}` },
        f.variants.map((v) => el("option", { value: v.tag, selected: v.tag === tag }, v.shortDesc || v.name)));
      select.addEventListener("change", () => { switchVariant(e, n, f, Number(select.value), title); renderManifest(); });
      container.append(fieldRow(f, name, select));
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
      const info = { title, field: { ...f, shortDesc: `${labelOf(f)} (entries)` }, e, n };
      const buttons = el("span", {},
        el("button", { disabled: length >= f.max, onclick: () => { stage(name, length + 1, info); renderManifest(); } }, "Add"),
        el("button", { disabled: length <= 0, onclick: () => { stage(name, length - 1, info); renderManifest(); } }, "Remove last"));
      container.append(fieldRow(f, name, el("span", {}, `${length} of ${f.max} `, buttons)), items);
    } else {
      container.append(leafRow(e, n, f, title));
    }
  }
}

function valueOf(name, field) {
  const v = name === null ? undefined : effective(name);
  return v === undefined ? defaultOf(name, field) : v;
}

function fieldRow(f, name, control) {
  const range = rangeText(f);
  return el("div", { class: "field" + (S.staged.has(name) ? " changed" : ""), "data-field": f.path, "data-name": name },
    el("label", { class: "label", title: f.longDesc || f.name }, labelOf(f)),
    el("span", { class: "control" }, control, f.unit && !range ? el("span", { class: "unit" }, f.unit) : null),
    range ? el("span", { class: "range" }, range) : null);
}

function showInvalid(row, control, name) {
  const bad = S.invalid.get(name);
  row.classList.toggle("invalid", Boolean(bad));
  row.querySelector(".error")?.remove();
  if (bad) {
    control.value = bad.text;
    row.append(el("span", { class: "error", role: "alert" }, `${bad.text}: ${bad.error}`));
  }
}

function leafRow(e, n, f, title) {
  const name = flatName(e, n, f.path);
  const kind = f.type.startsWith("float") ? "Float" : "Int32";
  const label = `${title} ${labelOf(f)}`;
  const value = valueOf(name, f);
  const info = { title, field: f, e, n, kind: f.type };
  let control;
  if (f.type === "bool") {
    control = el("input", { type: "checkbox", class: "switch", "data-name": name, checked: Boolean(value), "aria-label": label });
    control.addEventListener("change", () => { stage(name, control.checked ? 1 : 0, info); markRow(control, name); });
  } else if (f.values) {
    control = el("select", { "data-name": name, "aria-label": label },
      f.values.map((v) => el("option", { value: v.value, selected: v.value === value }, v.description)));
    control.addEventListener("change", () => { stage(name, Number(control.value), info); markRow(control, name); });
  } else {
    const hex = f.format === "hex";
    control = el("input", {
      type: "text", inputmode: kind === "Float" ? "decimal" : hex ? "text" : "numeric", "data-name": name,
      value: kind === "Float" ? shown(value, f.decimalPlaces) : numberText(value, hex), "aria-label": label,
    });
    control.addEventListener("input", () => {
      const row = control.closest(".field");
      const parsed = parseValue(control.value, kind, f.min, f.max, hex);
      if (parsed.error) {
        S.staged.delete(name); // an invalid entry is never sent
        S.invalid.set(name, { text: control.value, error: parsed.error });
        updatePending();
      } else {
        stage(name, roundFor(f, parsed.value), info);
      }
      showInvalid(row, control, name);
      markRow(control, name);
    });
  }
  const row = fieldRow(f, name, control);
  if (control.tagName === "INPUT" && control.type === "text") showInvalid(row, control, name);
  return row;
}

function markRow(control, name) {
  control.closest(".field")?.classList.toggle("changed", S.staged.has(name));
}

// -- "Add a device" ------------------------------------------------------------------------------

function renderPicker() {
  const root = $("#picker");
  root.replaceChildren();
  const groups = new Map();
  for (const d of S.picker) {
    if (!S.byName.has(d.parameter)) continue;
    if (!groups.has(d.group)) groups.set(d.group, []);
    groups.get(d.group).push(d);
  }
  for (const [group, entries] of groups) {
    const list = el("div", { class: "choices" });
    for (const d of entries) {
      const e = S.byName.get(d.parameter);
      const want = maskOf(e);
      const used = [...Array(e.max_instances).keys()].filter((k) => (want >> k) & 1).length;
      const free = [...Array(e.max_instances).keys()].find((k) => !((want >> k) & 1));
      list.append(el("div", { class: "choice", "data-parameter": d.parameter },
        el("div", { class: "chip" }, d.chips.join(", "), el("span", { class: "hint" }, d.driver ? `  ${d.driver}` : "")),
        el("div", { class: "needs" }, `needs ${d.needs}`),
        el("div", { class: "hint" }, `${used} of ${e.max_instances} configured`),
        el("button", {
          id: `add-${d.parameter}`, disabled: free === undefined,
          onclick: () => {
            const n = addInstance(e);
            renderManifest();
            document.querySelector(`.instance[data-instance="${titleOf(e, n)}"]`)?.scrollIntoView({ block: "nearest" });
          },
        }, free === undefined ? "All in use" : `Add ${titleOf(e, free)}`)));
    }
    root.append(el("section", { class: "kind-group", "data-group": group }, el("h3", {}, group), list));
  }
}

// -- classic parameters, as QGC's editor lists them ------------------------------------------------

function isModified(e, value) {
  return typeof e.default === "number" && typeof value === "number" && !sameStored(value, e.default, e.type);
}

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
    if (modifiedOnly && !isModified(e, effective(e.name))) continue;
    if (!groups.has(e.group || "Miscellaneous")) groups.set(e.group || "Miscellaneous", []);
    groups.get(e.group || "Miscellaneous").push(e);
  }
  for (const [group, entries] of [...groups].sort()) {
    const body = el("tbody");
    for (const e of entries) body.append(classicRow(e));
    root.append(el("div", { class: "group" }, el("h2", {}, group),
      el("table", {}, el("thead", {}, el("tr", {}, ["Parameter", "Value", "Default", ""].map((h) => el("th", {}, h)))), body)));
  }
  if (!groups.size) root.append(el("p", { class: "hint" }, "No parameter matches."));
}

function classicRow(e) {
  const value = effective(e.name);
  const modified = isModified(e, value);
  const row = el("tr", { class: (modified ? "modified" : "") + (S.staged.has(e.name) ? " changed" : ""), "data-param": e.name });
  const decimals = e.type === "Float" ? e.decimalPlaces : undefined;
  const bad = S.invalid.get(e.name);
  const input = el("input", { type: "text", value: bad ? bad.text : shown(value, decimals), "data-name": e.name, "aria-label": e.name });
  const error = el("div", { class: "error", role: "alert" }, bad ? `${bad.text}: ${bad.error}` : "");
  row.classList.toggle("invalid", Boolean(bad));
  const info = { title: e.name, field: { shortDesc: e.shortDesc, unit: e.units, type: e.type === "Float" ? "float32" : "int32", values: e.values }, kind: e.type };
  input.addEventListener("input", () => {
    const parsed = parseValue(input.value, e.type, e.min, e.max);
    row.classList.toggle("invalid", Boolean(parsed.error));
    error.textContent = parsed.error ? `${input.value}: ${parsed.error}` : "";
    if (parsed.error) { S.staged.delete(e.name); S.invalid.set(e.name, { text: input.value, error: parsed.error }); updatePending(); return; }
    stage(e.name, parsed.value, info);
    row.classList.toggle("changed", S.staged.has(e.name));
  });
  const reset = el("button", {
    disabled: !modified, title: `reset ${e.name} to its default`,
    onclick: () => { stage(e.name, e.default, info); renderClassic(); },
  }, "Reset");
  const range = rangeText(e);
  row.append(
    el("td", { class: "name" }, el("div", {}, e.name,
      e.rebootRequired ? el("span", { class: "reboot", title: "a change takes effect after a reboot" }, "reboot") : null),
      el("div", { class: "hint" }, e.shortDesc || "")),
    el("td", { class: "value" }, el("div", { class: "control" }, input, e.units ? el("span", { class: "unit" }, e.units) : null),
      range ? el("div", { class: "range" }, range) : null, error),
    el("td", { class: "default" }, shown(e.default)),
    el("td", {}, reset));
  return row;
}

// -- health --------------------------------------------------------------------------------

// Health reports of instances the vehicle still has (a removed instance's last report goes).
function visibleHealth() {
  return S.health.filter((h) => {
    const found = S.instanceOf.get(h.instance);
    if (!found) return true;
    return ((maskOf(found.e, S.values) >> found.n) & 1) === 1;
  });
}

function renderHealth() {
  const body = $("#health-table tbody");
  const shown = visibleHealth();
  body.replaceChildren(...shown.map((h) => el("tr", { "data-instance": h.instance },
    el("td", {}, h.instance), el("td", {}, h.driver), el("td", {}, (S.devicesNow.get(h.instance) || {}).location || h.location),
    el("td", { class: `state-${h.state}` }, h.state), el("td", {}, h.reason))));
  $("#health-empty").hidden = shown.length > 0;
  // Each message once, newest first, with how often it came.
  const seen = new Map();
  S.messages.forEach((m, i) => seen.set(m, { count: (seen.get(m)?.count || 0) + 1, last: i }));
  const lines = [...seen].sort((a, b) => b[1].last - a[1].last).slice(0, 30);
  $("#messages").replaceChildren(...lines.map(([text, { count }]) => el("li", {}, el("span", { class: "text" }, text),
    count > 1 ? el("span", { class: "count" }, `×${count}`) : null)));
  renderDeviceStatus();
}

// -- review and write ------------------------------------------------------------------------------

function sortedChanges() {
  return [...S.staged.values()].sort((a, b) =>
    (S.order.get(a.name) ?? 2) - (S.order.get(b.name) ?? 2) || a.name.localeCompare(b.name));
}

// The staged changes as review lines in words, each with the names it writes.
function reviewItems() {
  const items = [];
  const used = new Set();
  for (const e of S.structured) {
    if (e.max_instances === null) continue;
    const maskName = e.name + "_INST";
    if (!S.staged.has(maskName)) continue;
    used.add(maskName);
    const now = maskOf(e, S.values), want = S.staged.get(maskName).value;
    for (let n = 0; n < e.max_instances; n++) {
      const adds = (want >> n) & 1 && !((now >> n) & 1), removes = !((want >> n) & 1) && (now >> n) & 1;
      if (!adds && !removes) continue;
      const names = [maskName];
      const sets = [];
      for (const c of S.staged.values()) {
        if (!adds || c.e !== e || c.n !== n || c.name === maskName) continue;
        names.push(c.name); used.add(c.name);
        sets.push(c.tag ? `${labelOf(c.field)}: ${valueText(c.field, c.value)}` : `${labelOf(c.field)} ${valueText(c.field, c.value)}`);
      }
      const where = (adds ? S.devices : S.devicesNow).get(titleOf(e, n));
      items.push({
        names, mask: { name: maskName, bit: n, add: Boolean(adds) }, instance: titleOf(e, n),
        text: `${adds ? "add" : "remove"} ${titleOf(e, n)}${where ? ` (${where.location})` : ""}`,
        detail: sets.length ? `with ${sets.join(", ")}` : "",
      });
    }
  }
  for (const c of sortedChanges()) {
    if (used.has(c.name) || !c.tag) continue;
    used.add(c.name);
    const f = c.field;
    const from = f.variants.find((v) => v.tag === current(c.name));
    const to = f.variants.find((v) => v.tag === c.value);
    const names = [c.name];
    const sets = [];
    for (const x of S.staged.values()) {
      if (x.variantOf !== c.name) continue;
      names.push(x.name); used.add(x.name);
      sets.push(`${labelOf(x.field)} ${valueText(x.field, x.value)}`);
    }
    items.push({
      names, instance: c.title,
      text: `${c.title} ${c.union}: ${from ? from.shortDesc || from.name : "—"} → ${to.shortDesc || to.name}`,
      detail: sets.length ? `sets ${sets.join(", ")}` : "",
    });
  }
  for (const c of sortedChanges()) {
    if (used.has(c.name)) continue;
    const f = c.field || {};
    const label = c.e ? `${c.title} ${labelOf(f)}` : c.title || c.name;
    items.push({ names: [c.name], instance: c.e ? c.title : null,
      text: `${label}: ${valueText(f, current(c.name))} → ${valueText(f, c.value)}`, detail: c.name });
  }
  return items;
}

function resultText(item) {
  const results = item.names.map((n) => S.results.get(n)).filter(Boolean);
  if (!results.length) return "";
  const refused = results.find((r) => !r.ok);
  if (refused) return `refused: ${refused.reason}`;
  return `acknowledged: ${shown(results[0].value)}`;
}

async function openReview() {
  await refreshDevices();
  const body = $("#review-table tbody");
  body.replaceChildren();
  S.items = reviewItems();
  for (const item of S.items) {
    const result = resultText(item);
    body.append(el("tr", { "data-name": item.names[0], "data-names": item.names.join(" ") },
      el("td", {}, el("input", { type: "checkbox", checked: true, "aria-label": `write: ${item.text}` })),
      el("td", { class: "change" }, el("div", { class: "words" }, item.text), item.detail ? el("div", { class: "hint" }, item.detail) : null),
      el("td", { class: "result" + (result ? (result.startsWith("refused") ? " result-refused" : " result-ok") : "") }, result)));
  }
  // What the staged manifest would refuse at arming: flagged, still writable knowingly.
  const warnings = [...S.devices.values()].filter((d) => d.problems.length);
  $("#review-warnings").replaceChildren(...warnings.map((d) => el("li", { "data-instance": d.instance },
    `${d.instance} (${d.location}) cannot start: ${d.problems.join("; ")}. Arming will be refused.`)));
  $("#review-warnings").hidden = warnings.length === 0;
  $("#review-write").textContent = warnings.length ? "Write anyway" : "Write selected";
  $("#review-notes").textContent = S.notes.join(" ");
  const dialog = $("#review");
  if (!dialog.open) dialog.showModal();
}

async function writeSelected() {
  const rows = [...document.querySelectorAll("#review-table tbody tr")];
  const chosen = S.items.filter((_, i) => rows[i] && rows[i].querySelector("input").checked);
  const names = new Set(chosen.flatMap((item) => item.names));
  // An instance mask carries only the additions and removals chosen, with the mask they were
  // made from ("was"): the server applies those bits to the mask as it is then, so another
  // writer's instances added or removed meanwhile stay.
  const masks = new Map();
  for (const item of chosen) {
    if (!item.mask) continue;
    const m = item.mask;
    const v = masks.has(m.name) ? masks.get(m.name) : current(m.name) || 0;
    masks.set(m.name, m.add ? v | (1 << m.bit) : v & ~(1 << m.bit));
  }
  const changes = sortedChanges().filter((c) => names.has(c.name))
    .map((c) => masks.has(c.name)
      ? { name: c.name, value: masks.get(c.name), was: current(c.name) || 0 }
      : { name: c.name, value: c.value });
  if (!changes.length) return;
  $("#review-write").disabled = true;
  let instancesChanged = false;
  // In parts of at most the server's limit of changes per request, in order.
  const part = S.limits.changes || changes.length;
  for (let i = 0; i < changes.length; i += part) {
    const response = await fetch("/api/write", {
      method: "POST", headers: { "content-type": "application/json" },
      body: JSON.stringify({ changes: changes.slice(i, i + part) }),
    });
    const answer = await response.json();
    if (!response.ok) { $("#review-notes").textContent = answer.error; break; }
    S.values = answer.values;
    for (const r of answer.results) {
      S.results.set(r.name, r);
      if (r.ok && r.name.endsWith("_INST")) instancesChanged = true;
      const staged = S.staged.get(r.name);
      // a mask written with only some of its additions keeps the others staged (what was
      // asked, not what came back: another writer's instances are in that)
      if (!(r.ok && staged && masks.has(r.name) && staged.value !== masks.get(r.name))) S.staged.delete(r.name);
    }
  }
  rows.forEach((row, i) => {
    const cell = row.querySelector(".result");
    const text = resultText(S.items[i]);
    if (cell && text) { cell.textContent = text; cell.className = `result ${text.startsWith("refused") ? "result-refused" : "result-ok"}`; }
  });
  if (instancesChanged && S.mode === "mavlink") $("#gcs-notice").hidden = false;
  $("#review-write").disabled = false;
  updatePending();
  renderAll();
  refreshDevices();
}

async function loadFile(file) {
  const text = await file.text();
  const response = await fetch("/api/review", {
    method: "POST", headers: { "content-type": "application/json" },
    body: JSON.stringify({ filename: file.name, text }),
  });
  const answer = await response.json();
  if (!response.ok) { S.notes = [answer.error]; openReview(); return; }
  const fields = fieldsByName();
  for (const c of answer.changes) {
    const known = fields.get(c.name);
    const entry = S.byName.get(c.name);
    stage(c.name, c.new, known || { title: c.name, field: { shortDesc: entry?.shortDesc, unit: entry?.units }, kind: entry?.type });
  }
  S.notes = [`${file.name}: ${answer.changes.length} changes.`, ...answer.notes];
  renderAll();
  openReview();
}

// Every destructured name's leaf, for changes that arrive by name (a loaded file).
function fieldsByName() {
  const out = new Map();
  const walk = (e, n, fields) => {
    for (const f of fields) {
      if (f.role === "union_tag") {
        out.set(flatName(e, n, f.path), { title: titleOf(e, n), field: f, e, n, union: f.path.slice(0, -5), tag: true });
        for (const v of f.variants) walk(e, n, v.fields);
      } else if (f.role === "value") out.set(flatName(e, n, f.path), { title: titleOf(e, n), field: f, e, n, kind: f.type });
    }
  };
  for (const e of S.structured) for (let n = 0; n < (e.max_instances || 1); n++) walk(e, n, e.fields);
  return out;
}

// -- live values -------------------------------------------------------------------------------

function connect() {
  const ws = new WebSocket(`${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/ws`);
  ws.onmessage = (event) => {
    const msg = JSON.parse(event.data);
    if (msg.kind === "value") { S.values[msg.name] = msg.value; scheduleCheck(); }
    else if (msg.kind === "values") { S.values = msg.values; scheduleCheck(); }
    else if (msg.kind === "status") {
      S.messages.push(msg.text);
      S.messages.splice(0, Math.max(0, S.messages.length - 500));
      if (msg.health) {
        S.health = S.health.filter((h) => h.instance !== msg.health.instance).concat([msg.health]);
      }
      return scheduleHealth();
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

let healthPending = false;
function scheduleHealth() {
  if (healthPending) return;
  healthPending = true;
  requestAnimationFrame(() => { healthPending = false; renderHealth(); });
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
  $("#review-discard").addEventListener("click", () => {
    S.staged.clear(); S.invalid.clear(); updatePending(); $("#review").close(); renderAll(); scheduleCheck();
  });
  $("#review-all").addEventListener("change", (ev) => {
    document.querySelectorAll("#review-table tbody input").forEach((i) => { i.checked = ev.target.checked; });
  });
  $("#gcs-notice-close").addEventListener("click", () => { $("#gcs-notice").hidden = true; });
  $("#load").addEventListener("change", (ev) => { if (ev.target.files[0]) loadFile(ev.target.files[0]); ev.target.value = ""; });
  loadMemory();
  const [state, manifest] = await Promise.all([
    fetch("/api/state").then((r) => r.json()), fetch("/api/manifest").then((r) => r.json())]);
  S.meta = state.metadata; S.values = state.values; S.health = state.health; S.messages = state.messages;
  S.limits = state.limits || {};
  S.mode = state.mode;
  S.picker = manifest.drivers || [];
  S.drivers = new Map(S.picker.map((d) => [d.parameter, d]));
  const board = $("#board");
  board.append(...(manifest.boards || []).map((b) => el("option", { value: b.name }, `${b.label} (${b.name})`)));
  board.value = localStorage.getItem(BOARD_KEY) || "";
  if (board.selectedIndex < 0) board.value = "";
  board.addEventListener("change", () => { localStorage.setItem(BOARD_KEY, board.value); refreshDevices(); });
  $("#source").textContent = `${state.mode === "store" ? "offline store" : "vehicle"}: ${state.source}`;
  index();
  renderAll();
  updatePending();
  await refreshDevices();
  document.body.dataset.ready = "true";
  connect();
}

start();
