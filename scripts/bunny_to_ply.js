// Converts the npm package `bunny` (CommonJS: positions [[x,y,z]], cells [[a,b,c]] 0-based) to ASCII PLY.
// usage: node bunny_to_ply.js index.js out.ply
const fs = require('fs');
const path = require('path');
const [input, output] = process.argv.slice(2);
const bunny = require(path.resolve(input));
if (!Array.isArray(bunny.positions) || !Array.isArray(bunny.cells) || bunny.positions.length === 0) {
  console.error(`${input}: not the bunny package: positions/cells missing`);
  process.exit(1);
}
const lines = [
  'ply', 'format ascii 1.0', 'comment Stanford bunny from the npm package "bunny" (public domain)',
  `element vertex ${bunny.positions.length}`, 'property float x', 'property float y', 'property float z',
  `element face ${bunny.cells.length}`, 'property list uchar int vertex_indices', 'end_header',
];
for (const p of bunny.positions) lines.push(p.join(' '));
for (const c of bunny.cells) lines.push(`3 ${c.join(' ')}`);
fs.writeFileSync(output, lines.join('\n') + '\n');
