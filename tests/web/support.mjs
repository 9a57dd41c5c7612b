// What the web viewers' tests share: scan2lod's own server on a free port,
// headless Chromium (Debian's) through puppeteer-core with WebGL on
// SwiftShader, a record of every console error and failed request, the
// camera views the tests look from, and silhouettes of PNG pictures.
import { spawn, spawnSync } from 'node:child_process';
import { existsSync, readFileSync } from 'node:fs';
import { createRequire } from 'node:module';
import path from 'node:path';

export const kChromium = '/usr/bin/chromium';
export const kWidth = 640;
export const kHeight = 480;
export const kFovDegrees = 35;

// The npm packages tests/web/package.json pins, installed by scripts/build.sh
// into the build folder.
export function webModules(modulesDir) {
  if (!existsSync(path.join(modulesDir, 'puppeteer-core')))
    fail(`${modulesDir} holds no puppeteer-core: run scripts/build.sh deps (npm ci of tests/web)`);
  if (!existsSync(kChromium)) fail(`${kChromium} is missing: run scripts/build.sh deps (Debian's chromium)`);
  const require = createRequire(path.join(path.resolve(modulesDir), 'index.js'));
  return { puppeteer: require('puppeteer-core'), PNG: require('pngjs').PNG };
}

// Seconds since the call, as text with one decimal: the scripts' timing lines.
export function stopwatch() {
  const started = Date.now();
  return () => ((Date.now() - started) / 1000).toFixed(1);
}

export function fail(message) {
  console.error(`FAIL: ${message}`);
  process.exit(1);
}

// Assertions that report every failure, not only the first, with numbers.
export class Checks {
  constructor(name) { this.name = name; this.failures = 0; }
  that(ok, what) {
    console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
    if (!ok) this.failures++;
  }
  finish() {
    console.log(`${this.name}: ${this.failures ? `${this.failures} failed` : 'all passed'}`);
    process.exit(this.failures ? 1 : 0);
  }
}

export function runScan2lod(scan2lod, args) {
  const r = spawnSync(scan2lod, args, { encoding: 'utf8' });
  if (r.status !== 0) fail(`scan2lod ${args.join(' ')} exited with ${r.status}:\n${r.stdout}${r.stderr}`);
  return r.stdout;
}

// `scan2lod serve DIR --port 0`: resolves to { url, stop } once it prints its address.
export function serve(scan2lod, dir) {
  return new Promise((resolve, reject) => {
    const child = spawn(scan2lod, ['serve', dir, '--port', '0'], { stdio: ['ignore', 'pipe', 'pipe'] });
    let out = '';
    let err = '';
    const timer = setTimeout(() => { child.kill('SIGKILL'); reject(new Error(`serve printed no address: ${out}${err}`)); },
                             10000);
    child.stderr.on('data', (d) => { err += d; });
    child.stdout.on('data', (d) => {
      out += d;
      const m = out.match(/http:\/\/127\.0\.0\.1:(\d+)\//);
      if (!m) return;
      clearTimeout(timer);
      resolve({
        url: m[0],
        // SIGINT, as Ctrl-C: resolves to the exit code.
        stop: () => new Promise((done) => { child.on('exit', (code) => done(code)); child.kill('SIGINT'); }),
      });
    });
    child.on('exit', (code) => { clearTimeout(timer); reject(new Error(`serve exited with ${code}: ${out}${err}`)); });
  });
}

// SwiftShader gives WebGL 2 without a GPU through ANGLE's Vulkan backend
// (measured on Debian's chromium 156: --use-angle=swiftshader gives it;
// --use-gl=swiftshader gives no WebGL 2 at all). Asked for explicitly, as
// Chromium's silent fallback to software WebGL is deprecated.
export async function launchBrowser(puppeteer) {
  return puppeteer.launch({
    executablePath: kChromium,
    headless: true,
    args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--no-first-run', '--no-default-browser-check', '--disable-background-networking',
           '--disable-extensions', '--disable-component-update'],
  });
}

// Every console error, uncaught exception, failed request and HTTP error
// status the page meets, as lines of text.
export function watchPage(page) {
  const problems = [];
  const requests = [];
  page.on('console', (m) => { if (m.type() === 'error') problems.push(`console error: ${m.text()}`); });
  page.on('pageerror', (e) => problems.push(`uncaught: ${e.message}`));
  page.on('request', (r) => requests.push(r.url()));
  page.on('requestfailed', (r) => problems.push(`request failed: ${r.url()} (${r.failure()?.errorText})`));
  page.on('response', (r) => { if (r.status() >= 400) problems.push(`HTTP ${r.status()}: ${r.url()}`); });
  return { problems, requests };
}

// Waits until `page` answers true to `predicate` (a function run in the page)
// several times in a row: the view has settled.
export async function settle(page, predicate, what, timeoutMs = 60000) {
  const start = Date.now();
  let inARow = 0;
  while (Date.now() - start < timeoutMs) {
    inARow = (await page.evaluate(predicate)) ? inARow + 1 : 0;
    if (inARow >= 3) return Date.now() - start;
    await new Promise((r) => setTimeout(r, 100));
  }
  throw new Error(`${what} did not settle within ${timeoutMs / 1000} s`);
}

// The root tile's box in the tileset's frame (its transform a translation,
// as scan2lod writes it): centre and bounding-sphere radius.
export function tilesetSphere(tilesetJson) {
  const root = JSON.parse(readFileSync(tilesetJson, 'utf8')).root;
  const b = root.boundingVolume.box;
  const t = root.transform ? root.transform.slice(12, 15) : [0, 0, 0];
  const centre = [b[0] + t[0], b[1] + t[1], b[2] + t[2]];
  const length = (i) => Math.hypot(b[i], b[i + 1], b[i + 2]);
  return { centre, radius: Math.hypot(length(3), length(6), length(9)) };
}

// A view of the sphere from direction `dir` (from the centre towards the
// eye) at `distance` radii from the centre, +y up.
export function viewFrom({ centre, radius }, dir, distance) {
  const n = Math.hypot(...dir);
  const eye = centre.map((c, i) => c + (dir[i] / n) * distance * radius);
  return { eye, target: centre.slice(), up: [0, 1, 0], fov: kFovDegrees };
}

// The distance (in radii) at which the sphere just fills the narrower side.
export function framingDistance() {
  const half = (kFovDegrees / 2) * Math.PI / 180;
  return 1 / Math.sin(half) / Math.min(1, kWidth / kHeight);
}

export function cameraArgument(view) {
  return [...view.eye, ...view.target, ...view.up, view.fov].join(',');
}

// The pixels that differ from the background, taken as the colour of the
// top-left pixel (no test view puts the model there).
export function silhouette(PNG, bytes) {
  const png = PNG.sync.read(bytes);
  const { width, height, data } = png;
  const bg = [data[0], data[1], data[2]];
  const mask = new Uint8Array(width * height);
  let covered = 0;
  for (let i = 0; i < width * height; i++) {
    const d = Math.max(Math.abs(data[4 * i] - bg[0]), Math.abs(data[4 * i + 1] - bg[1]),
                       Math.abs(data[4 * i + 2] - bg[2]));
    mask[i] = d > 40 ? 1 : 0;
    covered += mask[i];
  }
  return { width, height, mask, coverage: covered / (width * height) };
}

export function intersectionOverUnion(a, b) {
  if (a.width !== b.width || a.height !== b.height)
    throw new Error(`pictures of different sizes: ${a.width}x${a.height} and ${b.width}x${b.height}`);
  let both = 0;
  let either = 0;
  for (let i = 0; i < a.mask.length; i++) {
    both += a.mask[i] & b.mask[i];
    either += a.mask[i] | b.mask[i];
  }
  return either ? both / either : 0;
}

export function pngFromDataUrl(url) {
  return Buffer.from(url.slice(url.indexOf(',') + 1), 'base64');
}
