// Renders a knitfit stocking.glb in three.js r170 (GLTFLoader, its default materials) inside
// headless Chromium, with the camera and lights of a camera.json from tools/client_pixels.py.
//
//   NODE_PATH=target/client-render/node_modules node tools/client_render/render.js \
//       CAMERA_JSON GLB OUT_DIR
//
// Writes OUT_DIR/{dressed,bare,black_leg,leg,stocking}.png (see tools/client_pixels.py).
// Chromium: $CHROMIUM or /usr/bin/chromium (Debian's package), software GL (SwiftShader).
// three.js is served from the same node_modules, by a local HTTP server on 127.0.0.1.
'use strict';
const fs = require('fs');
const http = require('http');
const path = require('path');
const puppeteer = require('puppeteer-core');

const [cameraPath, glbPath, outDir] = process.argv.slice(2);
if (!outDir) {
  console.error('usage: render.js CAMERA_JSON GLB OUT_DIR');
  process.exit(2);
}
const threeDir = path.dirname(path.dirname(require.resolve('three')));  // .../node_modules/three
const routes = {
  '/': [path.join(__dirname, 'page.html'), 'text/html'],
  '/camera.json': [cameraPath, 'application/json'],
  '/model.glb': [glbPath, 'model/gltf-binary'],
};

const server = http.createServer((req, res) => {
  const url = decodeURIComponent(req.url.split('?')[0]);
  let file, type;
  if (routes[url]) {
    [file, type] = routes[url];
  } else if (url.startsWith('/three/')) {
    file = path.join(threeDir, path.normalize(url.slice('/three/'.length)));
    type = file.endsWith('.js') ? 'text/javascript' : 'application/octet-stream';
    if (!file.startsWith(threeDir)) file = null;
  }
  if (url === '/favicon.ico') {
    res.writeHead(204);
    res.end();
    return;
  }
  if (!file || !fs.existsSync(file)) {
    res.writeHead(404);
    res.end();
    return;
  }
  res.writeHead(200, { 'Content-Type': type });
  fs.createReadStream(file).pipe(res);
});

(async () => {
  await new Promise((ok) => server.listen(0, '127.0.0.1', ok));
  const port = server.address().port;
  const cam = JSON.parse(fs.readFileSync(cameraPath, 'utf8'));
  const browser = await puppeteer.launch({
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
    headless: true,
    args: ['--no-sandbox', '--use-gl=angle', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
           '--ignore-gpu-blocklist', '--disable-gpu-sandbox'],
  });
  let code = 0;
  try {
    const page = await browser.newPage();
    const logs = [];
    page.on('console', (m) => logs.push(`${m.type()}: ${m.text()}`));
    page.on('pageerror', (e) => logs.push(`pageerror: ${e.message}`));
    await page.setViewport({ width: cam.width, height: cam.height, deviceScaleFactor: 1 });
    await page.goto(`http://127.0.0.1:${port}/`, { waitUntil: 'load' });
    await page.waitForFunction('window.pageReady === true', { timeout: 30000 });
    const out = await page.evaluate(() => window.renderAll());
    fs.mkdirSync(outDir, { recursive: true });
    for (const mode of ['dressed', 'bare', 'black_leg', 'leg', 'stocking']) {
      const png = Buffer.from(out[mode].split(',')[1], 'base64');
      fs.writeFileSync(path.join(outDir, `${mode}.png`), png);
    }
    console.log(`three.js: ${out.nodes.join(', ')} of ${out.scenes} scene(s), GL ${out.gl}`);
    for (const l of logs) console.log(`  page ${l}`);
  } catch (e) {
    console.error(`three.js render failed: ${e.message}`);
    code = 1;
  } finally {
    await browser.close();
    server.close();
  }
  process.exit(code);
})();
