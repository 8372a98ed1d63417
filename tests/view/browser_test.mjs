// csp view in a real browser (Debian's Chromium, headless, WebGL by SwiftShader), driven by
// Playwright (playwright-core from view/web's npm packages). What a person would see, checked in
// screenshots against references the page does not use:
//   - the arm where forward kinematics puts it: the flange and link origins computed here from
//     Franka's MDH table in ../shared/data/franka_models.json and the log's q, projected with the
//     camera the URL sets, land on arm-coloured pixels (the page's flat palette), at two times;
//   - the scene's obstacle drawn where the scene file puts it;
//   - the torque plot showing the logged curve (the CSV's own values at the plot's scales);
//   - a live run (csp emulate --view) keeps its cycle count and lost commands with a page attached,
//     and the page follows it; a run that dies leaves a clear message on the page; a page that
//     leaves is said in the terminal; a bad log is one clear error.
// Fails, never skips, when Chromium or the npm packages are missing. Screenshots stay in WORK.
//
//   node browser_test.mjs CSP WORK SOURCE_DIR SHARED_DATA_DIR
import { spawn, spawnSync } from "node:child_process";
import { createRequire } from "node:module";
import fs from "node:fs";
import path from "node:path";

const [csp, work, sourceDir, dataDir] = process.argv.slice(2);
if (!csp || !work || !sourceDir || !dataDir) throw new Error("usage: browser_test.mjs CSP WORK SOURCE_DIR SHARED_DATA_DIR");
const require = createRequire(path.join(sourceDir, "view", "web", "package.json"));
const { chromium } = require("playwright-core");
const { PNG } = require("pngjs");
fs.mkdirSync(work, { recursive: true });

let failures = 0;
function check(ok, what) {
  console.log(`${ok ? "ok  " : "FAIL"} ${what}`);
  if (!ok) failures += 1;
}

// --- Independent references: the MDH table, a pinhole camera, the CSV.
const models = JSON.parse(fs.readFileSync(path.join(dataDir, "franka_models.json"), "utf8"));
const mdh = models.kinematics.mdh_panda_fr3.rows;

const mul = (A, B) => A.map((row) => B[0].map((_, j) => row.reduce((s, a, k) => s + a * B[k][j], 0)));
function mdhTransform({ a, d, alpha, theta_offset: offset }, q) {   // RotX(alpha) TransX(a) RotZ(theta) TransZ(d)
  const [ca, sa, ct, st] = [Math.cos(alpha), Math.sin(alpha), Math.cos(q + offset), Math.sin(q + offset)];
  return [[ct, -st, 0, a], [st * ca, ct * ca, -sa, -d * sa], [st * sa, ct * sa, ca, d * ca], [0, 0, 0, 1]];
}
// Origins of frames 1..7 and the flange at q.
function origins(q) {
  let T = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]];
  return mdh.map((row, i) => {
    T = mul(T, mdhTransform(row, row.fixed ? 0 : q[i]));
    return [T[0][3], T[1][3], T[2][3]];
  });
}

// The camera the URL sets: position, target, z up, vertical field of view, the canvas's size.
function projector(eye, target, fovDeg, width, height) {
  const sub = (a, b) => a.map((x, i) => x - b[i]);
  const dot = (a, b) => a.reduce((s, x, i) => s + x * b[i], 0);
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const unit = (a) => a.map((x) => x / Math.hypot(...a));
  const back = unit(sub(eye, target));          // the camera looks along -back
  const right = unit(cross([0, 0, 1], back));
  const up = cross(back, right);
  const f = 1 / Math.tan((fovDeg * Math.PI) / 360);
  return (p) => {
    const r = sub(p, eye);
    const [x, y, z] = [dot(r, right), dot(r, up), -dot(r, back)];   // z > 0 in front
    return [width / 2 + (f * x / z) * (height / 2), height / 2 - (f * y / z) * (height / 2)];
  };
}

function readCsv(file) {
  const [header, ...lines] = fs.readFileSync(file, "utf8").trim().split("\n");
  const names = header.split(",");
  return lines.map((line) => Object.fromEntries(line.split(",").map((v, i) => [names[i], v])));
}

// --- Pixels.
const hex = (h) => [(h >> 16) & 255, (h >> 8) & 255, h & 255];
const ARM = hex(0xff6600), OBSTACLE = hex(0x0066ff), HIGHLIGHT = hex(0xff0000);
function near(png, [x, y], colours, radius) {   // some pixel within `radius` of (x, y) has one of the colours
  for (let dy = -radius; dy <= radius; ++dy) {
    for (let dx = -radius; dx <= radius; ++dx) {
      const px = Math.round(x) + dx, py = Math.round(y) + dy;
      if (px < 0 || py < 0 || px >= png.width || py >= png.height) continue;
      const i = 4 * (py * png.width + px);
      const pixel = [png.data[i], png.data[i + 1], png.data[i + 2]];
      if (colours.some((c) => c.every((v, k) => Math.abs(v - pixel[k]) <= 24))) return true;
    }
  }
  return false;
}

// --- csp.
function run(args) {
  const result = spawnSync(csp, args, { encoding: "utf8" });
  if (result.status !== 0) throw new Error(`csp ${args.join(" ")}: exit ${result.status}\n${result.stdout}${result.stderr}`);
  return result.stdout;
}

// Starts csp with `args`, resolves with the process and the page's address once csp prints it.
function serve(args) {
  const child = spawn(csp, args);
  child.output = "";
  child.errors = "";
  child.stderr.on("data", (d) => { child.errors += d; });
  child.exited = new Promise((resolve) => child.on("exit", (code, signal) => resolve({ code, signal })));
  return new Promise((resolve, reject) => {
    child.stdout.on("data", (d) => {
      child.output += d;
      const url = /view: (http:\/\/127\.0\.0\.1:\d+\/)/.exec(child.output);
      if (url) resolve({ child, url: url[1] });
    });
    child.exited.then(({ code }) => reject(new Error(`csp ${args.join(" ")} ended (${code}) before serving:\n${child.output}${child.errors}`)));
  });
}

const browser = await chromium.launch({
  executablePath: "/usr/bin/chromium",
  args: ["--headless=new", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--disable-gpu-sandbox",
         "--disable-background-networking", "--disable-component-update", "--no-first-run"],
});

async function openPage(url, query) {
  const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
  page.consoleErrors = [];
  page.on("console", (m) => { if (m.type() === "error") page.consoleErrors.push(m.text()); });
  page.on("pageerror", (e) => page.consoleErrors.push(String(e)));
  await page.goto(`${url}?${query}`);
  await page.waitForFunction(() => document.body.dataset.ready, null, { timeout: 120000 });
  return page;
}

try {
  // 1. A recorded run in a scene: the ultrasound scan, logged by csp emulate.
  const scenario = path.join(sourceDir, "configs", "scenarios", "medical", "ultrasound_abdomen_scan.yaml");
  const log = path.join(work, "scan.csv");
  run(["emulate", scenario, "--duration", "3", "--log", log]);
  const rows = readCsv(log);
  const { child, url } = await serve(["view", log, "--scenario", scenario, "--port", "0"]);
  const eye = [1.9, 1.4, 1.3], target = [0.4, 0.0, 0.3], fov = 40;
  const page = await openPage(url, `palette=flat&meshes=collision&camera=${eye}&target=${target}&fov=${fov}`);
  check(await page.evaluate(() => document.body.dataset.ready) === "1", "the page loaded the recording");
  const box = await page.locator("#scene").boundingBox();
  const project = projector(eye, target, fov, box.width, box.height);
  const description = await page.evaluate(() => window.cspView.description);

  // The arm at time t in a screenshot (`name`), checked against MDH forward kinematics of the logged q.
  async function checkArm(page, t, name) {
    const shown = await page.evaluate((t) => { window.cspView.setTime(t); return window.cspView.time; }, t);
    await page.waitForTimeout(200);
    const file = path.join(work, name);
    const png = PNG.sync.read(await page.locator("#scene").screenshot({ path: file }));
    // The row the page shows: the last frame at or before t; frames are log rows.
    const row = rows.filter((r) => Number(r.t) <= shown + 1e-9).pop();
    const q = [1, 2, 3, 4, 5, 6, 7].map((j) => Number(row[`q${j}`]));
    const o = origins(q);
    check(near(png, project(o[7]), [ARM], 3), `${name}, t = ${row.t} s: the flange is drawn where MDH forward kinematics puts it`);
    check(near(png, project(o[3]), [ARM], 3), `${name}: link 4's origin (the elbow) is on the arm`);
    check(near(png, project(o[1]), [ARM], 3), `${name}: link 2's origin is on the arm`);
    // A point in free space beside the elbow is not the arm (the check can fail).
    check(!near(png, project([o[3][0], o[3][1] - 0.3, o[3][2] + 0.3]), [ARM], 1), `${name}: 0.4 m beside the elbow is not the arm`);
    return o;
  }
  const early = await checkArm(page, 0.5, "scan_t1.png");
  const late = await checkArm(page, 2.5, "scan_t2.png");
  const moved = Math.hypot(...[0, 1].map((i) => project(early[7])[i] - project(late[7])[i]));
  check(moved > 10, `the flange moved between the two times (${moved.toFixed(0)} px on screen)`);
  // Franka's visual meshes (COLLADA, z-up in their link frames) land where the collision meshes do.
  const visual = await openPage(url, `palette=flat&meshes=visual&camera=${eye}&target=${target}&fov=${fov}`);
  await checkArm(visual, 2.5, "scan_t2_visual.png");
  check(visual.consoleErrors.length === 0, `no error in the visual page's console (${visual.consoleErrors.join("; ")})`);
  await visual.close();
  // A solid obstacle (the scene file's first box with a contact material: the cart under the base).
  const solid = description.scene.obstacles.find((o) => o.material && o.shape.type === "box");
  check(Boolean(solid), "the scene has a box with a material");
  {
    const png = PNG.sync.read(fs.readFileSync(path.join(work, "scan_t1.png")));
    const m = solid.shape.pose, h = solid.shape.half_size;
    const top = [0, 1, 2].map((i) => m[12 + i] + m[8 + i] * h[2]);   // centre + z axis * half height
    const corner = [0, 1, 2].map((i) => m[12 + i] + m[8 + i] * h[2] - m[i] * h[0] * 0.8);
    check(near(png, project(corner), [OBSTACLE], 3), `the ${solid.name} is drawn where the scene puts it`);
    check(near(png, project(top), [OBSTACLE, ARM], 3), `the ${solid.name}'s top centre is the obstacle (or the probe on it)`);
  }
  // A column chosen in the list gets a plot of its own, showing the logged curve: the CSV's values at
  // the plot's own scales (read from uPlot) land on the curve's colour.
  check((await page.evaluate(() => window.cspView.plots[0].columns[0])) === "tau_J1", "the first plot is the joint torques");
  await page.selectOption("#column", "tau_J2");
  await page.waitForFunction(() => window.cspView.plots.some((p) => p.columns[0] === "tau_J2" && p.data[0].length > 0));
  const plot = await page.evaluate(() => {
    const p = window.cspView.plots.find((p) => p.columns[0] === "tau_J2");
    p.element.scrollIntoView();
    const rect = p.u.over.getBoundingClientRect();
    return { left: rect.left, top: rect.top, width: rect.width, height: rect.height,
             x: [p.u.scales.x.min, p.u.scales.x.max], y: [p.u.scales.y.min, p.u.scales.y.max] };
  });
  const shot = PNG.sync.read(await page.screenshot({ path: path.join(work, "scan_page.png") }));
  let hits = 0, samples = 0;
  for (let i = 5; i < rows.length - 5; i += Math.floor(rows.length / 25)) {
    const t = Number(rows[i].t), v = Number(rows[i].tau_J2);
    const x = plot.left + ((t - plot.x[0]) / (plot.x[1] - plot.x[0])) * plot.width;
    const y = plot.top + ((plot.y[1] - v) / (plot.y[1] - plot.y[0])) * plot.height;
    samples += 1;
    if (near(shot, [x, y], [hex(0x1f77b4)], 2)) hits += 1;
  }
  check(hits === samples, `the tau_J2 curve is drawn at the logged values (${hits} of ${samples} samples)`);
  // The check can fail: the same samples 20 % of the plot's height higher are off the curve.
  let off = 0;
  for (let i = 5; i < rows.length - 5; i += Math.floor(rows.length / 25)) {
    const t = Number(rows[i].t), v = Number(rows[i].tau_J2) + 0.2 * (plot.y[1] - plot.y[0]);
    const x = plot.left + ((t - plot.x[0]) / (plot.x[1] - plot.x[0])) * plot.width;
    const y = plot.top + ((plot.y[1] - v) / (plot.y[1] - plot.y[0])) * plot.height;
    if (!near(shot, [x, y], [hex(0x1f77b4)], 2)) off += 1;
  }
  check(off === samples, `values the log does not have are not on the curve (${off} of ${samples})`);
  check(page.consoleErrors.length === 0, `no error in the page's console (${page.consoleErrors.join("; ")})`);
  await page.close();
  child.kill("SIGINT");
  const ended = await child.exited;
  check(ended.code === 0, `csp view ends on Ctrl-C with status 0 (${JSON.stringify(ended)})`);

  // 2. A live run: csp emulate --view on the real-time clock keeps its cycles with a page attached.
  const plain = run(["emulate", "default", "--clock", "realtime", "--duration", "2"]);
  const cycles = (text) => /ran (\d+) cycles/.exec(text)?.[1];
  const live = await serve(["emulate", "default", "--clock", "realtime", "--duration", "2", "--view", "--view-port", "0"]);
  const livePage = await openPage(live.url, "palette=flat&meshes=collision");
  await livePage.waitForFunction(() => document.getElementById("message").textContent.includes("the run ended"), null, { timeout: 60000 });
  const frames = await livePage.evaluate(() => window.cspView.frames.map((f) => f.t));
  check(frames.length >= 20, `the page got the live run's frames (${frames.length} in 2 s)`);
  check(frames.every((t, i) => i === 0 || t > frames[i - 1]), "the live frames' times increase");
  await livePage.screenshot({ path: path.join(work, "live.png") });
  await livePage.close();
  await new Promise((r) => setTimeout(r, 300));
  check(live.child.errors.includes("a page closed its connection"), "the terminal says the page left");
  live.child.kill("SIGINT");
  await live.child.exited;
  // Lost commands on the real-time clock depend on the machine's load, with or without a page: the
  // count is printed; the cycle count is the run's (csp_view_tests checks a viewed lockstep run is
  // the unviewed one bit for bit; csp_view_bench measures the cycle time with a page attached).
  check(cycles(live.child.output) === cycles(plain) && cycles(plain) === "2000",
        `the run keeps its cycles with a page attached (${cycles(live.child.output)} vs ${cycles(plain)}; ` +
        `${/lost commands \d+/.exec(live.child.output)} with the page, ${/lost commands \d+/.exec(plain)} without)`);

  // A bus's run (csp serve, no controller: the robot idles) is shown live too, and its end said.
  {
    const bus = await serve(["serve", "default", "--clock", "realtime", "--duration", "8", "--view", "--view-port", "0",
                             "--lcm-url", "udpm://239.255.76.67:7699?ttl=0"]);
    const busPage = await openPage(bus.url, "palette=flat&meshes=collision");
    await busPage.waitForFunction(() => document.getElementById("message").textContent.includes("the run ended"), null, { timeout: 60000 });
    const busFrames = await busPage.evaluate(() => window.cspView.frames.length);
    check(busFrames >= 5, `csp serve --view: the page got the bus's run (${busFrames} frames) and its end`);
    await busPage.close();
    await bus.child.exited;
  }

  // 3. The run's process dies under the page: the page says so.
  const dying = await serve(["emulate", "default", "--clock", "realtime", "--duration", "20", "--view", "--view-port", "0"]);
  const orphan = await openPage(dying.url, "palette=flat&meshes=collision");
  dying.child.kill("SIGKILL");
  await orphan.waitForFunction(() => !document.getElementById("message").hidden, null, { timeout: 30000 });
  const message = await orphan.evaluate(() => document.getElementById("message").textContent);
  check(message.includes("connection to csp closed"), `a closed socket is said on the page ("${message}")`);
  await orphan.close();

  // 4. A reflex where it happens: fr3_float is pushed into cartesian_reflex (a scenario, run by csp view).
  {
    const reflex = await serve(["view", "fr3_float", "--port", "0"]);
    const reflexPage = await openPage(reflex.url, "palette=flat&meshes=collision");
    const events = await reflexPage.evaluate(() => window.cspView.events);
    const first = events.find((e) => e.errors.length > 0);
    check(first && first.errors[0].name === "cartesian_reflex", `the reflex is an event with its libfranka name (${JSON.stringify(first)})`);
    const banner = await reflexPage.evaluate((t) => {
      window.cspView.setTime(t);
      const b = document.getElementById("banner");
      return { hidden: b.hidden, text: b.textContent };
    }, first.t);
    check(!banner.hidden && banner.text.includes("cartesian_reflex") && banner.text.includes(first.t.toFixed(3)),
          `the banner names the reflex and its time at that frame ("${banner.text}")`);
    const listed = await reflexPage.evaluate(() => [...document.querySelectorAll("#events li")].map((li) => li.textContent));
    check(listed.some((text) => text.includes("cartesian_reflex")), `the events list has it (${listed.join(" | ")})`);
    await reflexPage.screenshot({ path: path.join(work, "reflex.png") });
    await reflexPage.close();
    reflex.child.kill("SIGINT");
    await reflex.child.exited;
  }

  // 5. A bad log: one line naming it, exit status 2, nothing served.
  const bad = path.join(work, "bad.csv");
  fs.writeFileSync(bad, "t,q1\n0,abc\n");
  const refused = spawnSync(csp, ["view", bad, "--port", "0"], { encoding: "utf8" });
  check(refused.status === 2 && refused.stderr.trim().split("\n").length === 1 && refused.stderr.includes(bad),
        `a bad log is one error naming it (exit ${refused.status}: ${refused.stderr.trim()})`);
} finally {
  await browser.close();
}
console.log(failures === 0 ? "all checks passed" : `${failures} checks failed`);
process.exit(failures === 0 ? 0 : 1);
