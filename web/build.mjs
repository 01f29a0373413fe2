// Bundles three.js and the viewer (web/viewer.js and what it imports) into one script, and
// writes beside it the stamp that names the sources it was built from, one SHA-256 per file:
//   node build.mjs                      -> ../src/zoetic/web/static/viewer.js (+ viewer.sources.json)
//   node build.mjs --outfile DIR/x.js   -> DIR/x.js (+ DIR/viewer.sources.json)
// `npm run build` runs the first. The sources are every file under web/ but node_modules/; the
// stamp lets tests/test_viewer_bundle.py tell, without npm, that the shipped bundle is current.
import { createHash } from "node:crypto";
import { readdirSync, readFileSync, writeFileSync } from "node:fs";
import { dirname, join, relative, resolve } from "node:path";
import { fileURLToPath } from "node:url";
import { build } from "esbuild";

const here = dirname(fileURLToPath(import.meta.url));
const flag = process.argv.indexOf("--outfile");
const outfile =
  flag >= 0 ? resolve(process.argv[flag + 1]) : join(here, "../src/zoetic/web/static/viewer.js");

function sources(dir) {
  return readdirSync(dir, { withFileTypes: true }).flatMap((e) => {
    if (e.name === "node_modules") return [];
    const path = join(dir, e.name);
    return e.isDirectory() ? sources(path) : [path];
  });
}

const sha256 = (bytes) => createHash("sha256").update(bytes).digest("hex");

await build({
  entryPoints: [join(here, "viewer.js")],
  bundle: true,
  minify: true,
  format: "iife",
  legalComments: "none",
  target: "es2020",
  outfile,
  logLevel: "warning",
});
const stamp = { bundle: sha256(readFileSync(outfile)), sources: {} };
for (const path of sources(here).sort()) {
  stamp.sources["web/" + relative(here, path).split("\\").join("/")] = sha256(readFileSync(path));
}
writeFileSync(join(dirname(outfile), "viewer.sources.json"), JSON.stringify(stamp, null, 1) + "\n");
