// The viewer tests' command line and work folder: `node TEST.mjs PRT DATA_DIR WORK_DIR`. Shared by the tests that
// make their bundles with prt (glossy, hybrid_turns, methods, scene, scene_hybrid).
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';

// Reads PRT, DATA_DIR and WORK_DIR from the command line (exit 2 with a usage line naming `script` when one is
// missing), empties WORK_DIR, and returns {prt, data, work, file, run}: file(name) is a path in WORK_DIR, and
// run(...args) runs `prt --quiet ARGS` there as an argument list (no shell), returns its stdout, and throws with the
// command and its stderr when it exits non-zero.
export function testWorkspace(script) {
  const [prt, data, work] = process.argv.slice(2);
  if (!prt || !data || !work) {
    console.error(`usage: ${script} PRT DATA_DIR WORK_DIR`);
    process.exit(2);
  }
  fs.rmSync(work, { recursive: true, force: true });
  fs.mkdirSync(work, { recursive: true });
  const file = (name) => path.join(work, name);
  const run = (...args) => {
    const result = spawnSync(prt, ['--quiet', ...args], { encoding: 'utf8', cwd: work });
    if (result.status !== 0) throw new Error(`prt ${args.join(' ')} failed (${result.status}):\n${result.stderr}`);
    return result.stdout;
  };
  return { prt, data, work, file, run };
}
