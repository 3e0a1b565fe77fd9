// A smaller copy of a PNG for the docs (tools/docs/screenshots.sh), scaled by headless Debian
// chromium (tests/js/browser.js) so no image tool is needed: node shrink_png.js IN.png OUT.png WIDTH
'use strict';
const fs = require('fs');
const path = require('path');
const { launch } = require(path.join(__dirname, '../../tests/js/browser.js'));

async function main() {
  const [input, output, widthArg] = process.argv.slice(2);
  const png = fs.readFileSync(input);
  // The PNG's own size: the IHDR chunk's width and height (big-endian, bytes 16..23).
  const w = png.readUInt32BE(16), h = png.readUInt32BE(20);
  const width = Number(widthArg), height = Math.round((h * width) / w);
  const { browser, close } = await launch();
  try {
    const page = await browser.newPage();
    await page.setViewport({ width, height });
    await page.setContent('<body style="margin:0"><img id="i" style="display:block" ' +
      `width="${width}" height="${height}" src="data:image/png;base64,${png.toString('base64')}">`);
    await page.waitForFunction(() => document.getElementById('i').complete);
    await page.screenshot({ path: output, clip: { x: 0, y: 0, width, height } });
  } finally {
    await close();
  }
  process.stdout.write(`${output}: ${width}x${height} from ${w}x${h}\n`);
}
main().catch((e) => { console.error(`shrink_png: ${process.argv[2]}: ${e.message}`); process.exit(1); });
