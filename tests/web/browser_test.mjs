// The web app in headless Chromium, driven through its JavaScript API (window.seatTwin).
// Run by .ci/checks/web.sh:
//   node tests/web/browser_test.mjs BASE_URL REFERENCE.jsonl SEED DURATION_S SHOT_DIR
// REFERENCE.jsonl: one line per model (twin, linear, passive) from `cargo run --example
// web_aw` over `seat-twin simulate --scenario random --seed SEED --duration DURATION_S
// --rate 500`. Checks, in order:
//  1. the seeded random ride reproduces the CLI's a_w (and max |u|) to 1e-9 relative;
//  2. Kp set through the sliders' own path reaches the engine; a large |Kp| makes the loop
//     unstable, and "reset to last stable gains" brings it back;
//  3. a lesson step completes;
//  4. a shared link restores a setup, a bad one gives a message and the defaults;
//  5. the frame time at 1× with all plots (mean and 95th percentile), the real-time factor
//     at max speed, the time to the first live frame; screenshots at 1280×720, normal and in
//     presentation mode;
//  6. files: a preset through the browser's picker; downloads of the traces' CSV, the plots'
//     PNG and SVG and the preset's TOML (opened again through the picker);
//  7. background jobs in slices inside the frames: a sine dwell and a short Tune advance
//     their progress and deliver their result; a second Tune and a dwell are cancelled.
import { chromium } from "playwright-core";
import fs from "node:fs";
import path from "node:path";

const [base, refFile, seedArg, durationArg, shotDir] = process.argv.slice(2);
if (!shotDir) {
  console.error("usage: browser_test.mjs BASE_URL REFERENCE.jsonl SEED DURATION_S SHOT_DIR");
  process.exit(2);
}
const seed = Number(seedArg);
const presetFile = new URL("../../presets/tuned-paper.toml", import.meta.url).pathname;
const duration = Number(durationArg);
const ref = Object.fromEntries(
  fs.readFileSync(refFile, "utf8").trim().split("\n").map((l) => {
    const r = JSON.parse(l);
    return [path.basename(r.file, ".csv"), r];
  }),
);
const measured = {};
let failures = 0;
function check(ok, what) {
  console.log(`${ok ? "ok  " : "FAIL"} ${what}`);
  if (!ok) failures++;
}

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: [
    "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--use-gl=angle", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
  ],
});
const context = await browser.newContext({ viewport: { width: 1280, height: 720 } });

async function open(query, ctx = context) {
  const page = await ctx.newPage();
  page.on("pageerror", (e) => console.log(`page error: ${e}`));
  page.on("console", (m) => { if (m.type() === "error") console.log(`console: ${m.text()}`); });
  const t0 = Date.now();
  await page.goto(base + query);
  await page.waitForFunction(() => window.seatTwin && window.seatTwin.startedMs !== null,
    null, { timeout: 120000 });
  return { page, t0 };
}
const state = async (page) => JSON.parse(await page.evaluate(() => window.seatTwin.state()));
const jobs = async (page) => JSON.parse(await page.evaluate(() => window.seatTwin.jobs()));
// Polls the jobs every 50 ms until `done(j)`; returns every snapshot seen.
async function followJobs(page, done, timeoutMs) {
  const seen = [];
  const t0 = Date.now();
  for (;;) {
    const j = await jobs(page);
    seen.push(j);
    if (done(j)) return seen;
    if (Date.now() - t0 > timeoutMs) throw new Error(`jobs never ended: ${JSON.stringify(j)}`);
    await page.waitForTimeout(50);
  }
}
// The download that `action` starts: its file name and bytes.
async function downloaded(page, action) {
  const [d] = await Promise.all([page.waitForEvent("download", { timeout: 30000 }), action()]);
  return { name: d.suggestedFilename(), bytes: fs.readFileSync(await d.path()) };
}
const waitState = (page, predicate, arg, timeout = 120000) =>
  page.waitForFunction(([p, a]) => {
    const s = JSON.parse(window.seatTwin.state());
    return new Function("s", "a", `return (${p})`)(s, a);
  }, [predicate, arg], { timeout, polling: 50 });

try {
  // 1. The seeded random ride at max speed, paused at its end, against the CLI.
  {
    const { page, t0 } = await open(`?seed=${seed}&excitation=random&duration=${duration}&speed=max`);
    await waitState(page, "s.t_s > 0", null);
    measured.first_live_frame_ms = Date.now() - t0;
    const tRun = Date.now();
    await waitState(page, "!s.running && s.t_s >= a - 1e-9", duration, 300000);
    const wall = (Date.now() - tRun) / 1000;
    const s = await state(page);
    measured.rtf_max_speed = duration / wall;
    measured.engine_rtf = s.engine_rtf;
    check(Math.abs(s.t_s - duration) < 1e-6, `the ride ran to its end: t = ${s.t_s} s`);
    for (const m of ["twin", "linear", "passive"]) {
      const rel = Math.abs(s.aw[m] - ref[m].aw) / ref[m].aw;
      check(rel <= 1e-9, `a_w ${m}: web ${s.aw[m]} vs CLI ${ref[m].aw} m/s² (rel ${rel.toExponential(2)})`);
    }
    const relU = Math.abs(s.max_abs_u_m - ref.twin.max_abs_u_m) / ref.twin.max_abs_u_m;
    check(relU <= 1e-9, `max |u| twin: web ${s.max_abs_u_m} vs CLI ${ref.twin.max_abs_u_m} m (rel ${relU.toExponential(2)})`);
    check(s.stable === true && s.preset === "paper", `stable paper preset (${s.stable}, ${s.preset})`);
    await page.close();
  }

  // 2. Kp through the sliders' path; unstable; back to the last stable gains.
  {
    const { page } = await open("?speed=fast");
    await page.evaluate(() => window.seatTwin.setSlider("Kp", -12));
    let s = await state(page);
    check(s.kp_v_per_m === -12 && s.stable, `Kp = -12 V/m applied and stable (${s.kp_v_per_m}, ${s.stable})`);
    const refused = await page.evaluate(() => {
      try { window.seatTwin.setSlider("Kp", 5000); return null; } catch (e) { return String(e); }
    });
    check(refused && refused.includes("Kp"), `Kp = 5000 refused by the slider's range: ${refused}`);
    await page.waitForTimeout(500);
    await page.evaluate(() => window.seatTwin.setSlider("Kp", -2000));
    await waitState(page, "s.stable === false", null, 30000);
    s = await state(page);
    check(s.stable === false, `Kp = -2000 V/m: unstable (${s.error || "linear verdict"})`);
    await page.evaluate(() => window.seatTwin.resetToLastStableGains());
    await waitState(page, "s.stable === true && s.t_s > 0.5", null, 30000);
    s = await state(page);
    check(s.stable && s.kp_v_per_m === -12, `reset to the last stable gains: Kp = ${s.kp_v_per_m}, stable`);
    await page.evaluate(() => window.seatTwin.reset());
    await page.close();
  }

  // 3. A lesson step completes: step 3 (the delay), raise |Kp| until unstable.
  {
    const { page } = await open("");
    await page.evaluate(() => window.seatTwin.startLesson(3));
    let s = await state(page);
    check(s.lesson === 3 && !s.lesson_done, `lesson 3 started, not done yet`);
    for (const kp of [-50, -200, -800, -2000]) {
      await page.evaluate((k) => window.seatTwin.setSlider("Kp", k), kp);
      await page.waitForTimeout(300);
      s = await state(page);
      if (s.lesson_done) break;
    }
    check(s.lesson_done, `lesson 3 done after raising |Kp| to ${-s.kp_v_per_m} V/m`);
    await page.close();
  }

  // 4. A shared link restores a setup; a bad link gives a message and the defaults.
  let link;
  {
    const { page } = await open("");
    await page.evaluate(() => window.seatTwin.restore("#s=1;preset=tuned-predictive;exc=sine,0.5,6;speed=fast"));
    await page.evaluate(() => window.seatTwin.setSlider("Kp", -33.25));
    link = await page.evaluate(() => window.seatTwin.link());
    check(link.includes("#s=1;preset=tuned-predictive") && link.includes("controller.kp_v_per_m=-33.25"),
      `link: ${link}`);
    await page.close();
  }
  {
    const page = await context.newPage();
    await page.goto(link);
    await page.waitForFunction(() => window.seatTwin && window.seatTwin.startedMs !== null);
    const s = await state(page);
    check(s.preset === "tuned-predictive" && s.kp_v_per_m === -33.25,
      `the link restored preset ${s.preset}, Kp ${s.kp_v_per_m}`);
    const again = await page.evaluate(() => window.seatTwin.link());
    check(again === link, "the restored page gives the same link");
    await page.close();
  }
  {
    const { page } = await open("#s=1;preset=paper;valve.cd=7");
    const s = await state(page);
    check(s.preset === "paper" && s.kp_v_per_m === -5 && /valve\.cd/.test(s.notice || ""),
      `bad link: defaults and the message "${s.notice}"`);
    await page.close();
  }

  // 6 (before 5's fresh profile). Files: a preset through the browser's picker, the
  // traces' CSV as a download.
  {
    const { page } = await open("?speed=fast");
    // The call counts as a user gesture, so the picker opens at once (no rfd overlay).
    const [chooser] = await Promise.all([
      page.waitForEvent("filechooser", { timeout: 30000 }),
      page.evaluate(() => window.seatTwin.openPreset()),
    ]);
    await chooser.setFiles(presetFile);
    await waitState(page, 's.preset === "tuned-paper"', null, 30000);
    let s = await state(page);
    check(s.preset === "tuned-paper", `preset opened through the browser's picker: ${s.preset}`);
    await page.waitForTimeout(1500);
    const csv = await downloaded(page, () => page.evaluate(() => window.seatTwin.exportCsv()));
    const text = csv.bytes.toString("utf8");
    const rows = text.split("\n").filter((l) => /^[0-9-]/.test(l));
    check(csv.name === "traces.csv" && /^t,/m.test(text) && rows.length > 100,
      `CSV download ${csv.name}: ${rows.length} rows`);
    // The plots: every one as SVG (the web build draws no PNG); the first is checked.
    const names = [];
    page.on("download", (d) => names.push(d.suggestedFilename()));
    const svg = await downloaded(page, () => page.evaluate(() => window.seatTwin.exportPng()));
    const svgText = svg.bytes.toString("utf8");
    const polylines = (svgText.match(/<polyline/g) || []).length;
    check(/^plots-.*\.svg$/.test(svg.name) && /^<svg[^>]*width="\d+"/.test(svgText)
      && svgText.trimEnd().endsWith("</svg>") && polylines > 2 && /<text/.test(svgText),
      `SVG download ${svg.name}: ${svg.bytes.length} bytes, ${polylines} polylines`);
    await page.waitForTimeout(1500);
    check(names.length >= 2 && names.every((n) => /^plots-.*\.svg$/.test(n)),
      `plot downloads: ${names.join(", ")}`);
    // The preset with a changed Kp as TOML, then opened again through the picker.
    await page.evaluate(() => window.seatTwin.setSlider("Kp", -21.5));
    const toml = await downloaded(page, () => page.evaluate(() => window.seatTwin.savePreset()));
    const tomlText = toml.bytes.toString("utf8");
    check(toml.name === "tuned-paper.toml" && /kp_v_per_m\s*=\s*-21\.5\b/.test(tomlText),
      `preset download ${toml.name}: ${toml.bytes.length} bytes, Kp -21.5 in it`);
    const saved = path.join(shotDir, "..", "web-saved-preset.toml");
    fs.mkdirSync(path.dirname(saved), { recursive: true });
    fs.writeFileSync(saved, toml.bytes);
    await page.evaluate(() => window.seatTwin.setSlider("Kp", -3));
    const [again] = await Promise.all([
      page.waitForEvent("filechooser", { timeout: 30000 }),
      page.evaluate(() => window.seatTwin.openPreset()),
    ]);
    await again.setFiles(saved);
    await waitState(page, "s.kp_v_per_m === -21.5", null, 30000);
    s = await state(page);
    check(s.kp_v_per_m === -21.5, `the downloaded preset opens again: Kp ${s.kp_v_per_m}`);
    await page.close();
  }

  // 7. Background jobs in slices inside the frames (a browser tab has no threads).
  {
    const { page } = await open("?speed=1x");
    // The sine dwell: progress advances point by point, the points arrive.
    const tDwell = Date.now();
    await page.evaluate(() => window.seatTwin.startDwell());
    let seen = await followJobs(page, (j) => !j.dwell.running, 120000);
    measured.dwell_wall_s = (Date.now() - tDwell) / 1000;
    let dones = [...new Set(seen.map((j) => j.dwell.done))];
    let last = seen[seen.length - 1].dwell;
    check(dones.length >= 3 && last.points > 10 && !last.cancelled,
      `dwell in frames: progress ${dones.join(",")} of ${seen[0].dwell.total}, ${last.points} points`);
    // Cancelled half way.
    await page.evaluate(() => window.seatTwin.startDwell());
    await followJobs(page, (j) => j.dwell.done >= 2, 60000);
    await page.evaluate(() => window.seatTwin.cancelDwell());
    let j = await jobs(page);
    check(!j.dwell.running && j.dwell.cancelled && j.dwell.points < seen[0].dwell.total,
      `dwell cancelled at ${j.dwell.points} points`);
    // A short Tune: progress, then the result.
    const tTune = Date.now();
    await page.evaluate(() => window.seatTwin.startTune(6, 12));
    seen = await followJobs(page, (j) => !j.tune.running, 300000);
    measured.tune_6s_12evals_s = (Date.now() - tTune) / 1000;
    dones = [...new Set(seen.map((j) => j.tune.done))];
    last = seen[seen.length - 1].tune;
    check(dones.length >= 3 && last.result && last.message === null,
      `Tune in frames: progress ${dones.join(",")} of ${last.total}, result ${last.result}`);
    const ui = await state(page);
    check(ui.running, `the engine kept running during the Tune (t = ${ui.t_s.toFixed(1)} s)`);
    // Another, cancelled after its first evaluations.
    await page.evaluate(() => window.seatTwin.startTune(6, 40));
    await followJobs(page, (j) => j.tune.done >= 2, 120000);
    await page.evaluate(() => window.seatTwin.cancelTune());
    seen = await followJobs(page, (j) => !j.tune.running, 60000);
    last = seen[seen.length - 1].tune;
    check(/cancelled/.test(last.message || "") && last.done < 40,
      `Tune cancelled after ${last.done} evaluations: "${last.message}"`);
    await page.close();
  }

  // 5. Frame time at 1× with all plots; screenshots; the twin's own real-time factor.
  {
    // A fresh profile: the settings persist in the browser's storage (the link above set
    // "fast" and a platform sine), and the screenshots show the defaults.
    const fresh = await browser.newContext({ viewport: { width: 1280, height: 720 } });
    const { page, t0 } = await open("", fresh);
    // While the page starts, the dwell points are computed in the frames (one frequency per
    // slice): the frame times then, and after, from a fresh count.
    await followJobs(page, (j) => !j.dwell.running && j.dwell.points > 0, 120000);
    let s = await state(page);
    measured.start_with_dwell = { ui_ms_mean: s.ui_ms_mean, ui_ms_p95: s.ui_ms_p95,
      ui_ms_max: s.ui_ms_max, wall_s: (Date.now() - t0) / 1000 };
    await page.evaluate(() => window.seatTwin.resetFrameStats());
    // The browser's frame intervals over 5 s (requestAnimationFrame), beside the app's own
    // time per frame over the same frames.
    const intervals = await page.evaluate(() => new Promise((resolve) => {
      const t = [];
      const tick = (now) => {
        t.push(now);
        if (now - t[0] < 5000) requestAnimationFrame(tick); else resolve(t.slice(1).map((x, i) => x - t[i]));
      };
      requestAnimationFrame(tick);
    }));
    const sorted = [...intervals].sort((a, b) => a - b);
    measured.frame_interval_ms_mean = intervals.reduce((a, b) => a + b, 0) / intervals.length;
    measured.frame_interval_ms_p95 = sorted[Math.ceil(0.95 * sorted.length) - 1];
    s = await state(page);
    const wall = (Date.now() - t0) / 1000;
    measured.frames = intervals.length;
    measured.ui_ms_mean = s.ui_ms_mean;
    measured.ui_ms_p95 = s.ui_ms_p95;
    measured.ui_ms_max = s.ui_ms_max;
    // A measurement, stated, not a pass/fail check: on a loaded CI machine it varies.
    const met = s.ui_ms_mean <= 16 && s.ui_ms_p95 <= 16 ? "goal met" : "goal NOT met";
    console.log(`info 1× with all plots: ${s.ui_ms_mean.toFixed(1)} ms per frame mean, `
      + `${s.ui_ms_p95.toFixed(1)} ms 95th percentile over ${s.frames ?? intervals.length} frames `
      + `(goal ≤ 16 ms: ${met})`);
    measured.cpu_ms = s.cpu_ms;
    measured.fps = s.fps;
    measured.rtf_1x = s.rtf;
    check(s.running && s.t_s > 0.5 * wall && s.t_s < 1.05 * wall,
      `1×: running, t = ${s.t_s.toFixed(2)} s after ${wall.toFixed(1)} s of wall time`);
    fs.mkdirSync(shotDir, { recursive: true });
    await page.screenshot({ path: path.join(shotDir, "web-app.png") });
    await page.evaluate(() => { window.seatTwin.startLesson(5); window.seatTwin.setPresentation(true); });
    await page.waitForTimeout(3000);
    await page.screenshot({ path: path.join(shotDir, "web-presentation.png") });
    await page.evaluate(() => window.seatTwin.setPresentation(false));
    measured.twin_bench_rtf = await page.evaluate(() => window.seatTwin.benchTwin(5));
    await page.close();
  }
} catch (e) {
  console.log(`FAIL ${e.stack || e}`);
  failures++;
} finally {
  await browser.close();
}
console.log(`measured: ${JSON.stringify(measured)}`);
if (failures > 0) {
  console.log(`${failures} check(s) failed`);
  process.exit(1);
}
console.log("browser test passed");
