// homebot inspect: draws the whole states the server streams (GET /api/events), lets the user
// rewind through them with the timeline, and forwards control requests (POST /api/control/<verb>).
"use strict";

const NODE_W = 170, NODE_H = 38;
const states = [];           // every whole state so far, oldest first
let shown = -1;              // the index of the state on screen
let layoutKey = null;        // the tree structure the current drawing was laid out for
let positions = {};          // node id -> {x, y} from dagre
let selected = null;         // the selected behaviour's name
let controlState = null;     // the agent's last control reply
let info = {};

const $ = (id) => document.getElementById(id);
const SVG = "http://www.w3.org/2000/svg";

function element(tag, attributes, parent) {
  const node = document.createElementNS(SVG, tag);
  for (const [key, value] of Object.entries(attributes)) node.setAttribute(key, value);
  if (parent) parent.appendChild(node);
  return node;
}

function layout(tree) {
  const graph = new dagre.graphlib.Graph();
  graph.setGraph({ rankdir: "TB", nodesep: 14, ranksep: 34, marginx: 10, marginy: 10 });
  graph.setDefaultEdgeLabel(() => ({}));
  for (const node of tree) graph.setNode(node.id, { width: NODE_W, height: NODE_H });
  for (const node of tree) if (node.parent) graph.setEdge(node.parent, node.id);
  dagre.layout(graph);
  positions = {};
  for (const node of tree) positions[node.id] = graph.node(node.id);
  const size = graph.graph();
  const svg = $("graph");
  svg.setAttribute("width", size.width);
  svg.setAttribute("height", size.height);
  svg.innerHTML = "";
  const edges = element("g", { id: "edges" }, svg);
  for (const node of tree) {
    if (!node.parent) continue;
    const points = graph.edge(node.parent, node.id).points;
    element("path", { class: "edge", "data-from": node.parent, "data-to": node.id,
      d: "M" + points.map((p) => `${p.x},${p.y}`).join(" L") }, edges);
  }
  const nodes = element("g", { id: "nodes" }, svg);
  for (const node of tree) {
    const at = positions[node.id];
    const group = element("g", { class: "node", "data-id": node.id, "data-name": node.name,
      transform: `translate(${at.x - NODE_W / 2},${at.y - NODE_H / 2})` }, nodes);
    element("rect", { width: NODE_W, height: NODE_H, rx: 5 }, group);
    element("circle", { cx: NODE_W - 7, cy: 7, r: 4, fill: "none" }, group);
    const name = element("text", { x: 6, y: 14, class: "name" }, group);
    name.textContent = clip(`${node.name} [${node.type}]`, 30);
    element("text", { x: 6, y: 29, class: "message" }, group);
    element("title", {}, group).textContent = `${node.name} [${node.type}]`;
    group.addEventListener("click", () => select(node.name));
  }
}

function clip(text, length) {
  return text.length <= length ? text : text.slice(0, length - 1) + "…";
}

function draw(index) {
  const state = states[index];
  if (!state) return;
  shown = index;
  const key = JSON.stringify(state.tree);
  if (key !== layoutKey) { layout(state.tree); layoutKey = key; }
  const visited = new Set(state.visited);
  const breakpoints = new Set(controlState && controlState.ok ? controlState.breakpoints : []);
  for (const group of document.querySelectorAll("g.node")) {
    const [status, message] = state.behaviours[group.dataset.id] || ["INVALID", ""];
    group.setAttribute("data-status", status);
    group.setAttribute("data-visited", visited.has(group.dataset.id));
    group.setAttribute("data-selected", group.dataset.name === selected);
    group.setAttribute("data-breakpoint", breakpoints.has(group.dataset.name));
    group.querySelector("text.message").textContent = clip(message, 34);
  }
  for (const edge of document.querySelectorAll("path.edge")) {
    edge.setAttribute("data-visited", visited.has(edge.dataset.from) && visited.has(edge.dataset.to));
  }
  $("run").textContent = state.run;
  $("tick").textContent = state.tick;
  $("tree-status").textContent = state.status;
  $("position").textContent = `${index + 1} of ${states.length}`;
  $("timeline").value = index;
  fillTable($("messages"), state.tree.filter((n) => (state.behaviours[n.id] || ["", ""])[1])
    .map((n) => [n.name, state.behaviours[n.id][0], state.behaviours[n.id][1]]));
  fillTable($("blackboard"), Object.entries(state.blackboard));
  const writes = [];
  for (let i = index; i >= 0 && writes.length < 200; i--) {
    for (const item of [...states[i].activity].reverse()) writes.push([item.tick, item.by, item.op, item.key]);
  }
  fillTable($("activity"), writes.slice(0, 200));
  showSelected();
}

function fillTable(table, rows) {
  table.innerHTML = "";
  for (const row of rows) {
    const tr = table.insertRow();
    for (const cell of row) tr.insertCell().textContent = cell;
  }
}

function select(name) {
  selected = name;
  for (const id of ["breakpoint", "inject-failure", "inject-raise"]) $(id).disabled = !info.controls;
  if (shown >= 0) draw(shown);
}

function showSelected() {
  const state = states[shown];
  const node = state && state.tree.find((n) => n.name === selected);
  if (!node) { $("selected").textContent = "click a behaviour"; return; }
  const [status, message] = state.behaviours[node.id] || ["INVALID", ""];
  $("selected").textContent = `${node.name} [${node.type}] ${status}${message ? " — " + message : ""}`;
}

function add(state) {
  if (states.length && states[states.length - 1].run !== state.run) states.length = 0;
  states.push(state);
  $("timeline").max = states.length - 1;
  if ($("follow").checked) draw(states.length - 1);
  else $("position").textContent = `${shown + 1} of ${states.length}`;
}

async function control(verb, body) {
  const reply = await fetch(`/api/control/${verb}`, { method: "POST", body: JSON.stringify(body || {}) });
  showControl(await reply.json());
}

function showControl(reply) {
  const text = $("control-state");
  text.classList.toggle("error", !reply.ok);
  text.classList.toggle("paused", !!(reply.ok && reply.paused));
  if (!reply.ok) { text.textContent = reply.error; return; }
  controlState = reply;
  const parts = [reply.paused ? `paused${reply.paused_before ? " before " + reply.paused_before : ""}` : "running",
    `tick ${reply.tick}`];
  if (reply.breakpoints.length) parts.push(`breakpoints: ${reply.breakpoints.join(", ")}`);
  if (reply.faults.length) parts.push(`pending: ${reply.faults.map((f) => `${f.fault} in ${f.behaviour}`).join(", ")}`);
  if (reply.injected.length) parts.push(`injected: ${reply.injected.map((f) => `${f.fault} in ${f.behaviour} on tick ${f.tick}`).join(", ")}`);
  text.textContent = parts.join("; ");
  if (shown >= 0) draw(shown);
}

async function showOutcome() {
  const result = await (await fetch("/api/result")).json();
  if (result.status) {
    const injected = (result.injected || []).map((f) => `${f.fault} in ${f.behaviour} on tick ${f.tick}`);
    $("outcome").textContent = `${result.status}: ${result.reason}` + (injected.length ? `; injected ${injected.join(", ")}` : "");
  }
}

async function start() {
  info = await (await fetch("/api/info")).json();
  $("source").textContent = `${info.mode}: ${info.source}`;
  if (!info.controls) {
    for (const id of ["pause", "step", "continue"]) $(id).disabled = true;
    $("control-state").textContent = "a recorded run: no controls";
    showOutcome();
  } else {
    setInterval(() => { control("state"); showOutcome(); }, 1000);
    control("state");
  }
  $("timeline").addEventListener("input", (event) => {
    $("follow").checked = false;
    draw(Number(event.target.value));
  });
  $("follow").addEventListener("change", () => { if ($("follow").checked) draw(states.length - 1); });
  $("pause").addEventListener("click", () => control("pause"));
  $("step").addEventListener("click", () => control("step"));
  $("continue").addEventListener("click", () => control("continue"));
  $("breakpoint").addEventListener("click", () => control("breakpoint", { behaviour: selected,
    on: !(controlState && controlState.breakpoints && controlState.breakpoints.includes(selected)) }));
  $("inject-failure").addEventListener("click", () => control("inject", { behaviour: selected, fault: "failure" }));
  $("inject-raise").addEventListener("click", () => control("inject", { behaviour: selected, fault: "raise" }));
  const events = new EventSource("/api/events?from=0");
  events.onmessage = (event) => add(JSON.parse(event.data));
}

start();
