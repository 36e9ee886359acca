// Every page of the built site in a headless Chromium (the one @sparticuz/chromium ships inside itself):
// no console error, no page error, no failed request, every image and animation decoded.
//   node check.mjs SITE_DIR
// Prints one line per page with a problem and a summary; exit code 1 if any page has one.
import { createServer } from "node:http";
import { readFile, readdir, stat } from "node:fs/promises";
import { extname, join, relative, resolve, sep } from "node:path";
import chromium from "@sparticuz/chromium";
import puppeteer from "puppeteer-core";

const TYPES = {
  ".html": "text/html", ".js": "text/javascript", ".mjs": "text/javascript", ".css": "text/css",
  ".png": "image/png", ".gif": "image/gif", ".svg": "image/svg+xml", ".jpg": "image/jpeg", ".json": "application/json",
  ".woff2": "font/woff2", ".woff": "font/woff", ".ttf": "font/ttf", ".txt": "text/plain", ".ico": "image/x-icon",
};

async function pages(dir) {
  const out = [];
  for (const entry of await readdir(dir, { withFileTypes: true })) {
    const path = join(dir, entry.name);
    if (entry.isDirectory() && !entry.name.startsWith("_")) out.push(...(await pages(path)));
    else if (entry.isFile() && entry.name.endsWith(".html")) out.push(path);
  }
  return out;
}

function serve(root) {
  // the site over http (file:// forbids what the theme's scripts do); nothing outside ``root`` is served
  const server = createServer(async (req, res) => {
    const path = resolve(root, "." + decodeURIComponent(new URL(req.url, "http://x").pathname));
    if (!(path === root || path.startsWith(root + sep))) { res.writeHead(403).end(); return; }
    try {
      const file = (await stat(path)).isDirectory() ? join(path, "index.html") : path;
      res.writeHead(200, { "Content-Type": TYPES[extname(file)] ?? "application/octet-stream" });
      res.end(await readFile(file));
    } catch { res.writeHead(404).end(); }
  });
  return new Promise((ok) => server.listen(0, "127.0.0.1", () => ok(server)));
}

const root = resolve(process.argv[2] ?? "docs/_build/html");
const server = await serve(root);
const base = `http://127.0.0.1:${server.address().port}/`;
const browser = await puppeteer.launch({ args: chromium.args, executablePath: await chromium.executablePath(), headless: true });
let bad = 0, images = 0;
const all = await pages(root);
for (const file of all) {
  const url = base + relative(root, file).split(sep).join("/");
  const page = await browser.newPage();
  const problems = [];
  page.on("console", (m) => { if (m.type() === "error") problems.push(`console: ${m.text()}`); });
  page.on("pageerror", (e) => problems.push(`page error: ${e.message}`));
  page.on("requestfailed", (r) => problems.push(`request failed: ${r.url()} (${r.failure()?.errorText})`));
  page.on("response", (r) => { if (r.status() >= 400) problems.push(`HTTP ${r.status()}: ${r.url()}`); });
  await page.goto(url, { waitUntil: "networkidle0", timeout: 60000 });
  const imgs = await page.evaluate(async () => {
    const list = [...document.images];
    await Promise.all(list.map((i) => i.decode().catch(() => null)));  // decoded, or the failure noted below
    return list.map((i) => ({ src: i.currentSrc || i.src, ok: i.complete && i.naturalWidth > 0 }));
  });
  images += imgs.length;
  for (const i of imgs) if (!i.ok) problems.push(`image not decoded: ${i.src}`);
  if (problems.length) {
    bad += 1;
    console.log(`${relative(root, file)}:\n  ${problems.join("\n  ")}`);
  }
  await page.close();
}
await browser.close();
server.close();
console.log(`browser check: ${all.length} pages, ${images} images, ${bad} with problems`);
process.exit(bad ? 1 : 0);
