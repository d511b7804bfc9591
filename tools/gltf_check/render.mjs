// node render.mjs MODEL.glb WIDTH HEIGHT OUT.png [CHROMIUM]: three.js renders a glTF in headless Chromium.
import fs from "node:fs";
import http from "node:http";
import path from "node:path";
import { fileURLToPath } from "node:url";
import puppeteer from "puppeteer-core";

const here = path.dirname(fileURLToPath(import.meta.url));
const [model, width, height, out, chromium = "/usr/bin/chromium"] = process.argv.slice(2);
const types = { ".html": "text/html", ".js": "text/javascript", ".glb": "model/gltf-binary" };
const server = http.createServer((req, res) => {
  const url = decodeURIComponent(req.url.split("?")[0]);
  const file = url === "/" ? path.join(here, "page.html")
    : url === "/model.glb" ? model
    : url.startsWith("/three/") ? path.join(here, "node_modules", "three", url.slice(7)) : null;
  if (!file || !fs.existsSync(file)) { res.writeHead(404); res.end(); return; }
  res.writeHead(200, { "Content-Type": types[path.extname(file)] || "application/octet-stream" });
  fs.createReadStream(file).pipe(res);
});
await new Promise((ok) => server.listen(0, "127.0.0.1", ok));
const browser = await puppeteer.launch({
  executablePath: chromium,
  headless: true,
  args: ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist"],
});
try {
  const page = await browser.newPage();
  await page.goto(`http://127.0.0.1:${server.address().port}/?width=${width}&height=${height}`);
  await page.waitForFunction("window.done === true", { timeout: 120000 });
  const result = await page.evaluate(() => ({ error: window.error, pixels: window.pixels, renderer: window.renderer }));
  if (result.error) { console.error(`three.js: ${result.error}`); process.exitCode = 1; }
  else {
    fs.writeFileSync(out, Buffer.from(result.pixels.split(",")[1], "base64"));
    console.log(`wrote ${out} (WebGL: ${result.renderer})`);
  }
} finally { await browser.close(); server.close(); }
