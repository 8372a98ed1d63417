// csp view's page (docs/view.md): the arm with Franka's meshes, the scene, forces, paths and
// clearance in 3D, a timeline, and plots. csp computes every pose (forward kinematics in dynamics/);
// this page only places what it is given.
//
// URL parameters: t (the time shown first, s), camera=x,y,z and target=x,y,z (base frame, m), fov
// (deg), meshes=visual|collision, palette=flat (one flat colour per kind: the arm, the obstacles, the
// background; what the browser test reads in its screenshots), speed.
import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";
import { ColladaLoader } from "three/addons/loaders/ColladaLoader.js";
import { STLLoader } from "three/addons/loaders/STLLoader.js";
import { Plot } from "./plots.js";

const params = new URLSearchParams(location.search);
const flat = params.get("palette") === "flat";
const meshKind = params.get("meshes") === "collision" ? "collision" : "visual";
const numbers = (text, fallback) => (text ? text.split(",").map(Number) : fallback);

// Colours: the flat palette's are pure and unlit, so that a pixel tells what it shows.
const palette = flat
  ? { background: 0xffffff, arm: 0xff6600, obstacle: 0x0066ff, tissue: 0x0066ff, highlight: 0xff0000, path: 0x00aa00 }
  : { background: 0xf4f6f8, arm: 0xe8e8e8, obstacle: 0x8fa3b8, tissue: 0xe7b8a6, highlight: 0xe53935, path: 0x2e7d32 };

const view = {
  ready: false, time: 0, frames: [], events: [], plots: [], description: null, live: false,
  setTime: (t) => showTime(t),
};
window.cspView = view;

const $ = (id) => document.getElementById(id);
function say(text) {   // a problem the user must know: on the page and in the console
  $("message").textContent = text;
  $("message").hidden = false;
  console.error(`csp view: ${text}`);
}

async function getJson(path) {
  const response = await fetch(path);
  const body = await response.json().catch(() => ({ error: `${path}: not JSON` }));
  if (!response.ok) throw new Error(body.error ?? `${path}: HTTP ${response.status}`);
  return body;
}

// --- The 3D scene (the robot's base frame, z up).
const canvas = $("scene");
const renderer = new THREE.WebGLRenderer({ canvas, antialias: !flat, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
const scene = new THREE.Scene();
scene.background = new THREE.Color(palette.background);
const camera = new THREE.PerspectiveCamera(Number(params.get("fov") ?? 45), 1, 0.01, 50);
camera.up.set(0, 0, 1);
camera.position.fromArray(numbers(params.get("camera"), [1.7, 1.3, 1.1]));
const controls = new OrbitControls(camera, canvas);
controls.target.fromArray(numbers(params.get("target"), [0.35, 0, 0.35]));
controls.update();
controls.addEventListener("change", render);
if (!flat) {
  scene.add(new THREE.HemisphereLight(0xffffff, 0x666666, 2.2));
  const sun = new THREE.DirectionalLight(0xffffff, 1.6);
  sun.position.set(2, 1.5, 3);
  scene.add(sun);
  const grid = new THREE.GridHelper(2, 20, 0xb0b8c0, 0xd8dde2);
  grid.rotation.x = Math.PI / 2;   // the floor is z = 0
  scene.add(grid);
}

const material = (colour, opacity = 1) =>
  flat ? new THREE.MeshBasicMaterial({ color: colour })
       : new THREE.MeshStandardMaterial({ color: colour, roughness: 0.6, metalness: 0.1, transparent: opacity < 1, opacity });

function resize() {
  const { clientWidth: w, clientHeight: h } = canvas.parentElement;
  renderer.setSize(w, h, false);
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
  render();
}
window.addEventListener("resize", resize);
function render() { renderer.render(scene, camera); }

// A capsule from a to b (three's CapsuleGeometry lies along y, centred).
function capsuleMesh(c, mat) {
  const a = new THREE.Vector3(...c.a), b = new THREE.Vector3(...c.b);
  const length = a.distanceTo(b);
  const mesh = new THREE.Mesh(new THREE.CapsuleGeometry(c.radius, length, 6, 16), mat);
  mesh.position.copy(a).add(b).multiplyScalar(0.5);
  if (length > 0) mesh.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), b.clone().sub(a).normalize());
  return mesh;
}

const setPose = (object, m) => { object.matrix.fromArray(m); object.matrixWorldNeedsUpdate = true; };
function posed() { const g = new THREE.Group(); g.matrixAutoUpdate = false; scene.add(g); return g; }

// The robot: one group per link frame (0 = base, 1..7, 8 = flange), placed by each frame's poses.
const links = Array.from({ length: 9 }, posed);
const linkMaterials = [];   // per link, to highlight the joint an error is about
const colladaLoader = new ColladaLoader(), stlLoader = new STLLoader();

async function loadMesh(url) {
  if (url.endsWith(".stl")) return new THREE.Mesh(await stlLoader.loadAsync(url));
  const collada = await colladaLoader.loadAsync(url);
  // The meshes are in their link's frame, z up: the loader's turn of a Z_UP asset to three's y up
  // does not apply here (the scene is the robot's base frame, z up).
  collada.scene.rotation.set(0, 0, 0);
  return collada.scene;
}

function paint(object, mat) {
  object.traverse((child) => { if (child.isMesh) child.material = mat; });
}

async function buildRobot(robot) {
  for (let i = 0; i <= 8; ++i) linkMaterials.push(material(palette.arm));
  if (robot.meshes) {
    // franka_description's meshes are in their link's MDH frame; the FR3 has no visual mesh of
    // links 0, 6, 7 in the data set: their collision meshes stand in.
    const fr3Visual = [1, 2, 3, 4, 5];
    const url = (i) => {
      const visual = meshKind === "visual" && (robot.meshes === "fer" || fr3Visual.includes(i));
      return `/meshes/robot_arms/${robot.meshes}/${visual ? "visual" : "collision"}/link${i}.${visual ? "dae" : "stl"}`;
    };
    const meshes = await Promise.all([0, 1, 2, 3, 4, 5, 6, 7].map((i) => loadMesh(url(i))));
    meshes.forEach((mesh, i) => {
      if (flat || mesh.isMesh) paint(mesh, linkMaterials[i]);
      links[i].add(mesh);
    });
  } else {
    for (const c of robot.arm_capsules) links[c.frame].add(capsuleMesh(c.capsule, linkMaterials[c.frame]));
  }
  if (robot.hand) {   // the hand frame is the flange turned -45 deg about z (franka_description)
    const hand = new THREE.Group();
    hand.rotation.z = -Math.PI / 4;
    const base = "/meshes/robot_ee/franka_hand_white";
    const mesh = await loadMesh(meshKind === "visual" ? `${base}/visual/hand.dae` : `${base}/collision/hand.stl`);
    if (flat || mesh.isMesh) paint(mesh, linkMaterials[8]);
    hand.add(mesh);
    links[8].add(hand);
  }
  if (robot.tool) for (const c of robot.tool.capsules) links[8].add(capsuleMesh(c.capsule, linkMaterials[8]));
}

// The scene's obstacles (moving ones follow the frames' displacements) and the task's markers.
const obstacles = [];
function obstacleMesh(s, mat) {
  if (s.type === "box") {
    const mesh = new THREE.Mesh(new THREE.BoxGeometry(2 * s.half_size[0], 2 * s.half_size[1], 2 * s.half_size[2]), mat);
    mesh.matrixAutoUpdate = false;
    mesh.matrix.fromArray(s.pose);
    return mesh;
  }
  if (s.type === "capsule") return capsuleMesh(s, mat);
  if (s.type === "sphere") {
    const mesh = new THREE.Mesh(new THREE.SphereGeometry(s.radius, 32, 16), mat);
    mesh.position.fromArray(s.center);
    return mesh;
  }
  const mesh = new THREE.Mesh(new THREE.PlaneGeometry(3, 3), mat);   // a half-space: 3 m of its boundary plane
  mesh.position.fromArray(s.point);
  mesh.quaternion.setFromUnitVectors(new THREE.Vector3(0, 0, 1), new THREE.Vector3(...s.normal));
  return mesh;
}

function buildScene(description) {
  if (!description) return;
  description.obstacles.forEach((o) => {
    // A solid (it has a contact material: tissue, bone, furniture) is drawn solid; a zone the planner
    // only keeps clear of (the staff's) as its edges, so that it hides nothing.
    let mesh = obstacleMesh(o.shape, material(o.material && o.class === "patient" ? palette.tissue : palette.obstacle));
    if (!o.material) {
      const edges = new THREE.LineSegments(new THREE.EdgesGeometry(mesh.geometry), new THREE.LineBasicMaterial({ color: 0xc62828 }));
      edges.matrixAutoUpdate = mesh.matrixAutoUpdate;
      edges.matrix.copy(mesh.matrix);
      edges.position.copy(mesh.position);
      edges.quaternion.copy(mesh.quaternion);
      mesh = edges;
    }
    const holder = new THREE.Group();   // moved by the frames' displacements (breathing)
    holder.add(mesh);
    scene.add(holder);
    obstacles.push(holder);
  });
  const task = description.task;
  const lineMat = new THREE.LineBasicMaterial({ color: palette.path });
  if (task.type === "ultrasound_scan") {
    scene.add(new THREE.Line(new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(...task.start), new THREE.Vector3(...task.end)]), lineMat));
  } else if (task.type === "rcm_pivot") {
    const ring = new THREE.Mesh(new THREE.TorusGeometry(0.012, 0.002, 8, 32), material(palette.path));
    ring.position.fromArray(task.trocar);
    scene.add(ring);
  } else if (task.type === "burr_hole") {
    const entry = new THREE.Vector3(...task.entry), axis = new THREE.Vector3(...task.axis);
    scene.add(new THREE.ArrowHelper(axis, entry, 0.05, palette.path));
  }
}

// Paths: the end effector's measured path (and the desired one, where the log has q_d).
const pathMaterial = new THREE.LineBasicMaterial({ color: palette.path });
const plannedMaterial = new THREE.LineDashedMaterial({ color: 0x7b1fa2, dashSize: 0.01, gapSize: 0.006 });
let toolPath = null, plannedPath = null;
function drawPaths() {
  for (const line of [toolPath, plannedPath]) if (line) scene.remove(line);
  const frames = view.frames;
  toolPath = new THREE.Line(new THREE.BufferGeometry().setFromPoints(frames.map((f) => new THREE.Vector3(f.ee[12], f.ee[13], f.ee[14]))), pathMaterial);
  scene.add(toolPath);
  if (frames.length && frames[0].ee_d) {
    plannedPath = new THREE.Line(new THREE.BufferGeometry().setFromPoints(frames.map((f) => new THREE.Vector3(...f.ee_d))), plannedMaterial);
    plannedPath.computeLineDistances();
    scene.add(plannedPath);
  }
}

// Forces and clearance.
const forceArrow = new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(), 0.1, 0xd81b60, 0.02, 0.012);
forceArrow.visible = false;
scene.add(forceArrow);
const kMetresPerNewton = 0.005;   // 20 N draws 10 cm
const clearanceLine = new THREE.Line(new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), new THREE.Vector3()]),
                                     new THREE.LineBasicMaterial({ color: 0x00897b }));
clearanceLine.visible = false;
scene.add(clearanceLine);

// Each joint's position between its limits (the robot file's), as a bar with a mark: the limits a
// motion nears are seen before the reflex.
const kNearLimit = 0.05;   // of the joint's range
function showLimits(q) {
  const limits = view.description.robot.limits;
  const bars = $("hud-limits");
  if (!bars.children.length) {
    for (let j = 0; j < 7; ++j) bars.insertAdjacentHTML("beforeend", `<div class="joint">${j + 1}<div class="mark"></div></div>`);
  }
  q.forEach((value, j) => {
    const share = (value - limits.q_min[j]) / (limits.q_max[j] - limits.q_min[j]);
    const bar = bars.children[j];
    bar.querySelector(".mark").style.bottom = `${Math.min(1, Math.max(0, share)) * 31}px`;
    bar.classList.toggle("near", share < kNearLimit || share > 1 - kNearLimit);
    bar.title = `joint ${j + 1}: ${value.toFixed(3)} rad in [${limits.q_min[j]}, ${limits.q_max[j]}]`;
  });
}

// --- One frame on screen.
function showFrame(f) {
  setPose(links[0], new THREE.Matrix4().toArray());
  f.links.forEach((m, i) => setPose(links[i + 1], m));
  setPose(links[8], f.flange);
  const ee = new THREE.Vector3(f.ee[12], f.ee[13], f.ee[14]);
  if (f.force) {
    const force = new THREE.Vector3(...f.force);
    const size = force.length();
    forceArrow.visible = size > 0.5;   // below the estimate's noise: no arrow
    if (forceArrow.visible) {
      forceArrow.position.copy(ee);
      forceArrow.setDirection(force.clone().normalize());
      forceArrow.setLength(Math.min(0.5, size * kMetresPerNewton), 0.02, 0.012);
    }
    $("hud-force").textContent = `external force ${size.toFixed(1)} N`;
  }
  for (const [index, offset] of Object.entries(f.obstacles ?? {})) obstacles[Number(index)].position.fromArray(offset);
  if (f.clearance) {
    const c = f.clearance;
    clearanceLine.geometry.setFromPoints([new THREE.Vector3(...c.on_arm), new THREE.Vector3(...c.on_obstacle)]);
    clearanceLine.visible = true;
    const name = view.description.scene.obstacles[c.obstacle].name;
    $("hud-clearance").textContent = c.distance < 0 ? `in contact with ${name} (${(-1e3 * c.distance).toFixed(1)} mm deep)`
                                                    : `clearance ${(1e3 * c.distance).toFixed(1)} mm to ${name}`;
  }
  // Reflexes and errors where they happen: the joint in red, the names and the time.
  const errors = f.errors ?? [];
  linkMaterials.forEach((m, i) => m.color.setHex(errors.some((e) => e.joint + 1 === i) ? palette.highlight : palette.arm));
  $("hud-mode").textContent = f.mode ? `robot mode ${f.mode}` : "";
  const banner = $("banner");
  banner.hidden = errors.length === 0;
  if (errors.length) {
    banner.textContent = `${errors.map((e) => e.name + (e.joint >= 0 ? ` (joint ${e.joint + 1})` : "")).join(", ")} at t = ${f.t.toFixed(3)} s`;
  }
  $("hud-time").textContent = `t = ${f.t.toFixed(3)} s`;
  showLimits(f.q);
  render();
}

// The last frame at or before t.
function frameAt(t) {
  const frames = view.frames;
  let lo = 0, hi = frames.length - 1;
  while (lo < hi) {
    const mid = (lo + hi + 1) >> 1;
    if (frames[mid].t <= t) lo = mid; else hi = mid - 1;
  }
  return frames[lo];
}

function showTime(t) {
  if (!view.frames.length) return;
  const first = view.frames[0].t, last = view.frames[view.frames.length - 1].t;
  view.time = Math.min(last, Math.max(first, t));
  showFrame(frameAt(view.time));
  $("scrub").value = String((view.time - first) / Math.max(1e-9, last - first));
  $("clock").textContent = `${view.time.toFixed(3)} s`;
  for (const plot of view.plots) plot.showTime(view.time);
}

// --- Timeline.
let playing = false, lastTick = 0;
function tick(now) {
  if (!playing) return;
  const speed = Number($("speed").value);
  const last = view.frames[view.frames.length - 1].t;
  showTime(view.time + ((now - lastTick) / 1000) * speed);
  lastTick = now;
  if (view.time >= last && !view.live) { setPlaying(false); return; }
  requestAnimationFrame(tick);
}
function setPlaying(on) {
  playing = on && view.frames.length > 1;
  $("play").innerHTML = playing ? "&#10074;&#10074;" : "&#9654;";
  if (playing) {
    if (view.time >= view.frames[view.frames.length - 1].t) showTime(view.frames[0].t);
    lastTick = performance.now();
    requestAnimationFrame(tick);
  }
}
$("play").addEventListener("click", () => setPlaying(!playing));
document.addEventListener("keydown", (e) => { if (e.code === "Space") { e.preventDefault(); setPlaying(!playing); } });
$("scrub").addEventListener("input", () => {
  const first = view.frames[0].t, last = view.frames[view.frames.length - 1].t;
  showTime(first + Number($("scrub").value) * (last - first));
});

// --- Plots: the joint torques, the tracking error and the external force where the log has them,
// and any column the user picks.
const jointColumns = (prefix) => [1, 2, 3, 4, 5, 6, 7].map((j) => `${prefix}${j}`);
function defaultPlots(columns) {
  const plots = [["joint torque tau_J [N m]", jointColumns("tau_J")]];
  if (columns.includes("tracking_error1")) plots.push(["tracking error q_d - q [rad]", jointColumns("tracking_error")]);
  if (columns.includes("force_norm")) plots.push(["external force |F| [N]", ["force_norm"]]);
  return plots.filter(([, names]) => names.every((n) => columns.includes(n)));
}

async function addPlot(title, names) {
  const plot = new Plot($("plots"), title, names, $("plots").clientWidth || 440);
  view.plots.push(plot);
  if (!view.live) plot.setSeries(await getJson(`/api/series?names=${names.map(encodeURIComponent).join(",")}`));
  plot.showTime(view.time);
  return plot;
}

function listColumns(columns) {
  const select = $("column");
  for (const name of columns) select.add(new Option(name, name));
  select.addEventListener("change", () => { if (select.value) addPlot(select.value, [select.value]).catch((e) => say(e.message)); select.value = ""; });
}

function listEvents(events) {
  const list = $("events");
  for (const e of events) {
    const item = document.createElement("li");
    const names = e.errors.map((x) => x.name + (x.joint >= 0 ? ` (joint ${x.joint + 1})` : "")).join(", ");
    item.textContent = `${e.t.toFixed(3)} s: ${e.mode ?? ""} ${names}`.trim();
    item.addEventListener("click", () => showTime(e.t));
    list.appendChild(item);
  }
}

// --- A recorded run, or a live one.
async function loadRecording() {
  const recording = await getJson("/api/recording");
  view.frames = recording.frames;
  view.events = recording.events;
  $("source").textContent = recording.source;
  drawPaths();
  listEvents(recording.events);
  listColumns(recording.columns);
  for (const [title, names] of defaultPlots(recording.columns)) await addPlot(title, names);
  showTime(Number(params.get("t") ?? recording.frames[0].t));
}

// After a live run whose log was written (--log, --csv): the whole run, at the log's full rate.
async function showRecordingOf(socket) {
  socket.close();
  view.live = false;
  for (const plot of view.plots) plot.element.remove();
  view.plots = [];
  $("column").length = 1;
  await loadRecording();
}

const kLiveSeconds = 600;   // a live page keeps this much of the run to scrub back through
function goLive() {
  view.live = true;
  const socket = new WebSocket(`ws://${location.host}/api/live`);
  let ended = false;
  socket.onmessage = async (message) => {
    const m = JSON.parse(message.data);
    if (m.type === "end") {
      ended = true;
      say(`the run ended: ${m.text}` + (m.recording ? " (the whole run is loaded)" : ""));
      if (m.recording) await showRecordingOf(socket);
      return;
    }
    view.frames.push(m);
    while (view.frames.length > 2 && m.t - view.frames[0].t > kLiveSeconds) view.frames.shift();
    if (view.plots.length === 0) {
      const columns = Object.keys(m.values);
      listColumns(columns);
      for (const [title, names] of defaultPlots(columns)) await addPlot(title, names);
    }
    for (const plot of view.plots) plot.append(m.t, m.values, 10);
    if (!playing) showTime(m.t);   // follows the run unless the user scrubs back
    view.ready = true;
    document.body.dataset.ready = "1";
  };
  socket.onclose = () => { if (!ended) say("the connection to csp closed: the run or csp stopped"); };
  socket.onerror = () => say(`cannot reach csp at ${location.host}: is the run still going?`);
}

async function main() {
  resize();
  try {
    view.description = await getJson("/api/description");
    $("title").textContent = view.description.title ?? "csp view";
    await buildRobot(view.description.robot);
    buildScene(view.description.scene);
    if (view.description.live) goLive();
    else {
      await loadRecording();
      view.ready = true;
      document.body.dataset.ready = "1";
    }
  } catch (error) {
    say(error.message);
    document.body.dataset.ready = "error";
  }
}
main();
