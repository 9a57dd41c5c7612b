// node three_viewer.mjs SCAN2LOD DIR NODE_MODULES: the page export writes
// beside a tileset (delivery/web/), served by `scan2lod serve`, in headless
// Chromium. DIR holds the fixture (bunny_tileset.mjs): bunny.mco and its
// tileset folder bunny/. Claims:
//   - the model is drawn, and its silhouette matches VTK's render of the
//     full-detail model from the same camera (scan2lod render --camera);
//   - the page requests more tiles, and draws deeper ones, as the camera
//     approaches;
//   - nothing on the console is an error, and no request fails.
import { readFileSync, writeFileSync } from 'node:fs';
import path from 'node:path';
import {
  Checks, cameraArgument, framingDistance, intersectionOverUnion, kHeight, kWidth, launchBrowser, pngFromDataUrl,
  runScan2lod, serve, settle, silhouette, stopwatch, tilesetSphere, viewFrom, watchPage, webModules,
} from './support.mjs';

const [scan2lod, dir, modules] = process.argv.slice(2);
const { puppeteer, PNG } = webModules(modules);
const checks = new Checks('three.js viewer');
const tileset = path.join(dir, 'bunny');
const sphere = tilesetSphere(path.join(tileset, 'tileset.json'));
// Oblique, so that the silhouette has the ears, the back and the feet.
const direction = [0.6, 0.35, 1];
const far = viewFrom(sphere, direction, 4 * framingDistance());
const framed = viewFrom(sphere, direction, 0.9 * framingDistance());
const near = viewFrom(sphere, direction, 1.1);

const seconds = stopwatch();

// VTK's picture of the full-detail model from the framed view, beforehand.
const vtkPng = path.join(dir, 'three_vtk.png');
runScan2lod(scan2lod, ['render', path.join(dir, 'bunny.mco'), '--percent', '100', '--mode', 'shaded',
                       '--size', `${kWidth}x${kHeight}`, '--camera', cameraArgument(framed), '--no-captions',
                       '-o', vtkPng, '-q']);
console.log(`VTK render: ${seconds()} s`);

const server = await serve(scan2lod, tileset);
const browser = await launchBrowser(puppeteer);
try {
  const page = await browser.newPage();
  await page.setViewport({ width: kWidth, height: kHeight, deviceScaleFactor: 1 });
  const watched = watchPage(page);
  const idle = () => window.scan2lod.stats().idle;
  const stats = () => page.evaluate(() => window.scan2lod.stats());

  // Far: the page opens on the view its address names.
  await page.goto(`${server.url}index.html?camera=${cameraArgument(far)}`, { waitUntil: 'load' });
  await page.evaluate(() => window.scan2lod.ready);
  await settle(page, idle, 'the far view');
  const atFar = await stats();
  console.log(`far view (${seconds()} s): ${JSON.stringify(atFar)}`);
  const camera = await page.evaluate(() => window.scan2lod.camera());
  const gap = Math.max(...camera.eye.map((v, i) => Math.abs(v - far.eye[i])));
  checks.that(gap < 1e-6 * sphere.radius, `the address sets the camera: eye off by ${gap}`);

  // Framed: the silhouette against VTK's.
  await page.evaluate((v) => window.scan2lod.setCamera(v.eye, v.target, v.up, v.fov), framed);
  await settle(page, idle, 'the framed view');
  const atFramed = await stats();
  console.log(`framed view (${seconds()} s): ${JSON.stringify(atFramed)}`);
  const shot = pngFromDataUrl(await page.evaluate(() => window.scan2lod.snapshot()));
  writeFileSync(path.join(dir, 'three_page.png'), shot);
  const drawn = silhouette(PNG, shot);
  const reference = silhouette(PNG, readFileSync(vtkPng));
  const iou = intersectionOverUnion(drawn, reference);
  checks.that(atFramed.tilesDrawn > 0 && atFramed.trianglesDrawn > 0,
              `the model is drawn: ${atFramed.tilesDrawn} tiles, ${atFramed.trianglesDrawn} triangles`);
  checks.that(drawn.coverage > 0.05, `it covers ${(100 * drawn.coverage).toFixed(1)} % of the picture (VTK: ` +
                                     `${(100 * reference.coverage).toFixed(1)} %)`);
  checks.that(iou >= 0.9, `silhouette IoU against VTK's render from the same camera: ${iou.toFixed(4)} (>= 0.9)`);

  // Near: the camera inside the root's sphere, next to the surface.
  await page.evaluate((v) => window.scan2lod.setCamera(v.eye, v.target, v.up, v.fov), near);
  await settle(page, idle, 'the near view');
  const atNear = await stats();
  console.log(`near view (${seconds()} s): ${JSON.stringify(atNear)}`);
  checks.that(atFar.requested > 0 && atFramed.requested > atFar.requested && atNear.requested > atFramed.requested,
              `tiles requested grow as the camera approaches: ${atFar.requested} far, ${atFramed.requested} ` +
              `framed, ${atNear.requested} near`);
  checks.that(atNear.deepestDrawn > atFar.deepestDrawn,
              `deeper tiles are drawn near: depth ${atNear.deepestDrawn} near, ${atFar.deepestDrawn} far`);
  checks.that(atNear.failed === 0, `no tile failed to load (${atNear.failed})`);

  const readout = await page.$eval('#readout', (e) => e.textContent);
  checks.that(/\d+ tiles drawn · [\d,]+ triangles/.test(readout), `the readout shows what is drawn: "${readout}"`);
  const foreign = watched.requests.filter((u) => !u.startsWith(server.url) && !u.startsWith('data:'));
  checks.that(foreign.length === 0, `every request went to the served folder (${foreign.join(' ') || 'none elsewhere'})`);
  checks.that(watched.problems.length === 0, `no console error and no failed request, over ` +
              `${watched.requests.length} requests${watched.problems.length ? ':\n  ' + watched.problems.join('\n  ') : ''}`);
} finally {
  await browser.close();
  const code = await server.stop();
  checks.that(code === 0, `serve stops on SIGINT with exit code 0 (${code})`);
}
console.log(`total: ${seconds()} s`);
checks.finish();
