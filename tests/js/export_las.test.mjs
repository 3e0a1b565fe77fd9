// `sweepmap export las` read back by an independent reader, @loaders.gl/las (its LAZRsLoader:
// the default LASLoader, laz-perf, reads LAS 1.0-1.3 only and refuses 1.4): the point count,
// the bounds and a sample of points equal those of the PLY files the LAS was made from (read
// here by their header). loaders.gl does not return the GPS time or the header's version
// fields, so those are read here from the bytes, at the offsets of ASPRS LAS 1.4 R15.
// Intensity: each sampled point's LAS intensity, as the reader decodes it, is its PLY vertex's
// float intensity rounded and clipped to 0..65535 (mapping/las_io.hpp's lasIntensity), or 0 where
// the PLY has none; EXPECT_INTENSITY=all requires every PLY to carry it (and not all zero), none
// that no PLY does.
// Usage: [EXPECT_INTENSITY=all|none] node export_las.test.mjs LAS PLY...
import fs from "fs";
import path from "path";

const here = path.dirname(new URL(import.meta.url).pathname);
const lasDir = path.join(here, "node_modules/@loaders.gl/las");
function check(ok, what) {
  if (!ok) throw new Error("check failed: " + what);
}

// Node's fetch cannot load the decoder's WASM from a file: URL; give it the bytes instead.
async function lazRsLoader() {
  const init = (await import(path.join(lasDir, "dist/libs/laz-rs-wasm/laz_rs_wasm.js"))).default;
  await init({ module_or_path: fs.readFileSync(path.join(lasDir, "dist/libs/laz-rs-wasm/laz_rs_wasm_bg.wasm")) });
  return (await import(path.join(lasDir, "dist/index.js"))).LAZRsLoader;
}

// x, y, z of a binary little-endian PLY with float x y z first in its vertex element, and its
// float intensity property (null without).
function readPly(file) {
  const b = fs.readFileSync(file);
  const end = b.indexOf("end_header\n") + "end_header\n".length;
  const header = b.toString("latin1", 0, end);
  check(header.includes("format binary_little_endian 1.0"), file + ": binary little-endian");
  const count = Number(/element vertex (\d+)/.exec(header)[1]);
  const props = [...header.matchAll(/property (\w+) (\w+)/g)];
  check(props[0][2] === "x" && props[1][2] === "y" && props[2][2] === "z" && props[0][1] === "float", file);
  const stride = props.reduce((s, p) => s + ({ float: 4, double: 8, uchar: 1, ushort: 2 })[p[1]], 0);
  const out = new Float64Array(3 * count);
  for (let i = 0; i < count; ++i) {
    for (let k = 0; k < 3; ++k) out[3 * i + k] = b.readFloatLE(end + i * stride + 4 * k);
  }
  const at = props.findIndex((p) => p[2] === "intensity");
  let intensity = null;
  if (at >= 0) {
    check(props[at][1] === "float", file + ": float intensity");
    const offset = props.slice(0, at).reduce((s, p) => s + ({ float: 4, double: 8, uchar: 1, ushort: 2 })[p[1]], 0);
    intensity = new Float64Array(count);
    for (let i = 0; i < count; ++i) intensity[i] = b.readFloatLE(end + i * stride + offset);
  }
  return { xyz: out, intensity };
}

// lasIntensity (mapping/las_io.cpp): rounded (halves away from zero), clipped to 0..65535.
function lasIntensity(v) {
  return v > 0 ? Math.round(Math.min(v, 65535)) : 0;
}

async function main() {
  const [lasFile, ...plyFiles] = process.argv.slice(2);
  const read = plyFiles.map(readPly);
  const plys = read.map((r) => r.xyz);
  const ply = new Float64Array(plys.reduce((n, p) => n + p.length, 0));
  plys.reduce((at, p) => (ply.set(p, at), at + p.length), 0);
  const n = ply.length / 3;
  const plyIntensity = new Float64Array(n);  // 0 where a PLY has none
  read.reduce((at, r) => (r.intensity && plyIntensity.set(r.intensity, at), at + r.xyz.length / 3), 0);
  const expect = process.env.EXPECT_INTENSITY;
  if (expect === "all") check(read.every((r) => r.intensity) && plyIntensity.some((v) => v > 0), "every PLY has intensities");
  if (expect === "none") check(read.every((r) => !r.intensity), "no PLY has intensities");

  const buf = fs.readFileSync(lasFile);
  const { parse } = await import("@loaders.gl/core");
  const las = await parse(buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.length), await lazRsLoader(), { worker: false });
  const pos = las.attributes.POSITION.value;
  check(las.header.vertexCount === n && pos.length === 3 * n, `point count ${las.header.vertexCount} = PLY ${n}`);

  // The header: version 1.4, format 6 of 30 bytes, legacy counts 0, the 64-bit count.
  const dv = new DataView(buf.buffer, buf.byteOffset, buf.length);
  check(buf.toString("latin1", 0, 4) === "LASF" && buf[24] === 1 && buf[25] === 4, "LAS 1.4");
  check(buf[104] === 6 && dv.getUint16(105, true) === 30, "point data record format 6, 30 bytes");
  check(dv.getUint32(107, true) === 0 && Number(dv.getBigUint64(247, true)) === n, "point counts");
  const scale = dv.getFloat64(131, true);
  const tolerance = scale / 2 + 1e-5; // quantisation, and loaders.gl's float32 positions

  // Bounds: the reader's bounding box and the PLY's.
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < 3 * n; ++i) {
    lo[i % 3] = Math.min(lo[i % 3], ply[i]);
    hi[i % 3] = Math.max(hi[i % 3], ply[i]);
  }
  const [bmin, bmax] = las.header.boundingBox;
  for (let k = 0; k < 3; ++k) {
    check(Math.abs(bmin[k] - lo[k]) <= tolerance && Math.abs(bmax[k] - hi[k]) <= tolerance, `bounds axis ${k}`);
  }
  // A sample of points, in order, with their intensities.
  const lasIntensities = las.attributes.intensity.value;
  check(lasIntensities.length === n, "an intensity per point");
  const step = Math.max(1, Math.floor(n / 500));
  let sampled = 0, nonzero = 0;
  for (let i = 0; i < n; i += step, ++sampled) {
    for (let k = 0; k < 3; ++k) {
      check(Math.abs(pos[3 * i + k] - ply[3 * i + k]) <= tolerance, `point ${i} axis ${k}: ${pos[3 * i + k]} vs ${ply[3 * i + k]}`);
    }
    const want = lasIntensity(Math.fround(plyIntensity[i]));
    check(lasIntensities[i] === want, `point ${i} intensity ${lasIntensities[i]} vs PLY ${plyIntensity[i]} (${want})`);
    nonzero += lasIntensities[i] > 0;
  }
  if (expect === "all") check(nonzero > 0, "some sampled intensity above 0");
  const gps = n > 0 ? dv.getFloat64(dv.getUint32(96, true) + 22, true) : 0;
  console.log(JSON.stringify({ las: lasFile, bytes: buf.length, points: n, sampled, sampled_with_intensity: nonzero, first_gps_time: gps, bounds: [lo, hi] }));
}

main().catch((e) => {
  console.error(e.stack || String(e));
  process.exit(1);
});
