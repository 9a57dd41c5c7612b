// node cesium_viewer.mjs SCAN2LOD DIR NODE_MODULES: the fixture's tileset
// (bunny_tileset.mjs, in DIR/bunny/) in CesiumJS, npm cesium's prebuilt
// Build/Cesium, in headless Chromium. The test puts the page (cesium.html,
// cesium_page.js), Cesium's files and a copy of the tileset in one folder and
// serves it with `scan2lod serve`: same origin, no network, no Cesium ion.
// Claims: CesiumJS loads the tileset and draws it (its silhouette matches
// VTK's render from the same camera), with no console error and no failed
// request.
import { cpSync, mkdirSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import {
  Checks, cameraArgument, framingDistance, intersectionOverUnion, kHeight, kWidth, launchBrowser, pngFromDataUrl,
  runScan2lod, serve, settle, silhouette, stopwatch, tilesetSphere, viewFrom, watchPage, webModules,
} from './support.mjs';

const [scan2lod, dir, modules] = process.argv.slice(2);
const { puppeteer, PNG } = webModules(modules);
const checks = new Checks('CesiumJS');
const here = path.dirname(fileURLToPath(import.meta.url));
const seconds = stopwatch();

// The served folder: the page, Cesium (without its 10 MB of ES-module
// copies, which the page does not load) and the tileset.
const site = path.join(dir, 'cesium_site');
rmSync(site, { recursive: true, force: true });
mkdirSync(site, { recursive: true });
const cesium = path.join(modules, 'cesium', 'Build', 'Cesium');
for (const part of ['Cesium.js', 'Assets', 'ThirdParty', 'Widgets', 'Workers'])
  cpSync(path.join(cesium, part), path.join(site, 'cesium', part), { recursive: true });
cpSync(path.join(here, 'cesium.html'), path.join(site, 'index.html'));
cpSync(path.join(here, 'cesium_page.js'), path.join(site, 'cesium_page.js'));
cpSync(path.join(dir, 'bunny'), path.join(site, 'tileset'), { recursive: true });

const sphere = tilesetSphere(path.join(site, 'tileset', 'tileset.json'));
const view = viewFrom(sphere, [-0.8, 0.3, 1], 0.9 * framingDistance());
const vtkPng = path.join(dir, 'cesium_vtk.png');
runScan2lod(scan2lod, ['render', path.join(dir, 'bunny.mco'), '--percent', '100', '--mode', 'shaded',
                       '--size', `${kWidth}x${kHeight}`, '--camera', cameraArgument(view), '--no-captions',
                       '-o', vtkPng, '-q']);
console.log(`site and VTK render: ${seconds()} s`);

const server = await serve(scan2lod, site);
const browser = await launchBrowser(puppeteer);
try {
  const page = await browser.newPage();
  await page.setViewport({ width: kWidth, height: kHeight, deviceScaleFactor: 1 });
  const watched = watchPage(page);
  await page.goto(`${server.url}index.html`, { waitUntil: 'load' });
  await page.evaluate(() => window.cesiumTest.ready);
  await page.evaluate((v) => window.cesiumTest.setCamera(v.eye, v.target, v.up, v.fov), view);
  await settle(page, () => window.cesiumTest.stats().idle, 'CesiumJS');
  const stats = await page.evaluate(() => window.cesiumTest.stats());
  console.log(`settled (${seconds()} s): ${JSON.stringify(stats)}`);
  const shot = pngFromDataUrl(await page.evaluate(() => window.cesiumTest.snapshot()));
  writeFileSync(path.join(dir, 'cesium_page.png'), shot);
  const drawn = silhouette(PNG, shot);
  const reference = silhouette(PNG, readFileSync(vtkPng));
  const iou = intersectionOverUnion(drawn, reference);

  checks.that(stats.loaded > 0 && stats.selected > 0 && stats.triangles > 0,
              `CesiumJS loads and draws tiles: ${stats.loaded} loaded, ${stats.selected} selected, ` +
              `${stats.triangles} triangles`);
  checks.that(stats.failed === 0, `no tile failed (${stats.failed})`);
  checks.that(drawn.coverage > 0.05, `it covers ${(100 * drawn.coverage).toFixed(1)} % of the picture (VTK: ` +
                                     `${(100 * reference.coverage).toFixed(1)} %)`);
  checks.that(iou >= 0.9, `silhouette IoU against VTK's render from the same camera: ${iou.toFixed(4)} (>= 0.9)`);
  const foreign = watched.requests.filter((u) => !u.startsWith(server.url) && !u.startsWith('data:') &&
                                                 !u.startsWith('blob:'));
  checks.that(foreign.length === 0, `every request went to the served folder (${foreign.join(' ') || 'none elsewhere'})`);
  checks.that(watched.problems.length === 0, `no console error and no failed request, over ` +
              `${watched.requests.length} requests${watched.problems.length ? ':\n  ' + watched.problems.join('\n  ') : ''}`);
} finally {
  await browser.close();
  await server.stop();
}
console.log(`total: ${seconds()} s`);
checks.finish();
