// node bunny_tileset.mjs SCAN2LOD BUN_CONF DIR: the web tests' fixture. Builds
// the bundled bunny's model at a modest resolution into DIR/bunny.mco and
// exports it as a tileset, with the page, into DIR/bunny/; small tiles, so
// that the tree is deep enough for refinement to show.
import { existsSync, mkdirSync } from 'node:fs';
import path from 'node:path';
import { fail, runScan2lod } from './support.mjs';

const [scan2lod, conf, dir] = process.argv.slice(2);
mkdirSync(dir, { recursive: true });
const model = path.join(dir, 'bunny.mco');
let start = Date.now();
runScan2lod(scan2lod, ['build', conf, '-o', model, '-r', '64', '-q']);
console.log(`model: ${((Date.now() - start) / 1000).toFixed(1)} s`);
start = Date.now();
const report = JSON.parse(runScan2lod(scan2lod, ['export', model, '--format', '3dtiles', '--tile-triangles', '1500',
                                                 '-o', path.join(dir, 'bunny'), '--json']));
console.log(`tileset: ${report.tiles} tiles, depth ${report.depth}, page ${report.page.join(' ')}, ` +
            `${((Date.now() - start) / 1000).toFixed(1)} s`);
for (const file of ['index.html', 'viewer.js'])
  if (!report.page.includes(file) || !existsSync(path.join(dir, 'bunny', file)))
    fail(`export --format 3dtiles wrote no ${file} beside tileset.json (page: ${JSON.stringify(report.page)})`);
if (report.depth < 2) fail(`the tileset is ${report.depth} deep; the tests need refinement to show`);
