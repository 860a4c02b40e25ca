// Reads LAS files with two readers that rvlio did not write and prints, as one
// JSON document on stdout, what each of them found (test/outputs/las/las_reader_test.cpp
// compares it with what rvlio wrote; docs/outputs.md "Checked by other readers"):
//
//   loaders   @loaders.gl/las (LAZRsLoader, its LAS 1.4 reader): the header's version, point format,
//             count, scale, offset and bounds; every point's x y z (fp64) and
//             intensity.
//   copc      the LAS 1.4 module of the copc package: the header (global
//             encoding, counts, offsets), the VLRs (user id, record id, the
//             WKT and text payloads), the extra-bytes descriptors, and every
//             point's X Y Z, Intensity, GpsTime, UserData, ReturnNumber,
//             NumberOfReturns, Classification, PointSourceId and extra-bytes
//             values.
//
// usage: node read_las.mjs FILE.las...
import { readFileSync } from 'node:fs';
import { LAZRsLoader } from '@loaders.gl/las';
import { Las } from 'copc';
// The loader's WebAssembly part fetches its .wasm file by URL, which Node's
// fetch does not do for file: URLs; given its bytes it loads, once (the
// loader's own init then finds it loaded). Imported by path: the package
// exports only its entry point.
import initLazRs from './node_modules/@loaders.gl/las/dist/libs/laz-rs-wasm/laz_rs_wasm.js';

await initLazRs({ module_or_path: readFileSync(new URL(
    './node_modules/@loaders.gl/las/dist/libs/laz-rs-wasm/laz_rs_wasm_bg.wasm', import.meta.url)) });

function bufferOf(path) {
  const b = readFileSync(path);
  return new Uint8Array(b.buffer, b.byteOffset, b.byteLength);
}

function arrayBufferOf(bytes) {
  return bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);
}

// JSON has no NaN or infinity: strings that the C++ side turns back.
function num(v) {
  if (typeof v === 'bigint') return Number(v);
  if (typeof v !== 'number') return v;
  if (Number.isNaN(v)) return 'nan';
  if (!Number.isFinite(v)) return v > 0 ? 'inf' : '-inf';
  return v;
}

async function readWithLoaders(bytes) {
  const mesh = await LAZRsLoader.parse(arrayBufferOf(bytes), { las: { fp64: true, colorDepth: 'auto' } });
  const h = mesh.loaderData;
  return {
    version: h.versionAsString,
    format: h.pointsFormatId,
    record_length: h.pointsStructSize,
    count: h.pointsCount,
    scale: h.scale,
    offset: h.offset,
    mins: h.mins,
    maxs: h.maxs,
    positions: Array.from(mesh.attributes.POSITION.value),
    intensity: Array.from(mesh.attributes.intensity.value),
  };
}

async function readWithCopc(bytes) {
  const header = Las.Header.parse(bytes.slice(0, 375));
  const get = async (begin, end) => bytes.slice(begin, end);
  const vlrs = await Las.Vlr.walk(get, header);
  const out = {
    global_encoding: header.globalEncoding,
    version: `${header.majorVersion}.${header.minorVersion}`,
    system_identifier: header.systemIdentifier,
    generating_software: header.generatingSoftware,
    header_length: header.headerLength,
    point_data_offset: header.pointDataOffset,
    format: header.pointDataRecordFormat,
    record_length: header.pointDataRecordLength,
    count: num(header.pointCount),
    count_by_return: header.pointCountByReturn.map(num),
    legacy_count: new DataView(bytes.buffer, bytes.byteOffset).getUint32(107, true),
    scale: header.scale,
    offset: header.offset,
    min: header.min,
    max: header.max,
    evlr_count: header.evlrCount,
    vlrs: [],
    extra_bytes: [],
    points: {},
  };
  let eb = [];
  for (const v of vlrs) {
    const payload = await Las.Vlr.fetch(get, v);
    const entry = { user_id: v.userId, record_id: v.recordId, description: v.description,
                    length: v.contentLength };
    if ((v.userId === 'LASF_Projection' && v.recordId === 2112) ||
        (v.userId === 'LASF_Spec' && v.recordId === 3)) {
      const text = new TextDecoder().decode(payload);
      entry.text = text.replace(/\0+$/, '');
      entry.null_terminated = text.endsWith('\0');
    }
    if (v.userId === 'LASF_Spec' && v.recordId === 4) eb = Las.ExtraBytes.parse(payload);
    out.vlrs.push(entry);
  }
  out.extra_bytes = eb.map((e) => ({ name: e.name, type: e.type, length: e.length,
                                     nodata: num(e.nodata), min: num(e.min), max: num(e.max) }));
  const start = header.pointDataOffset;
  const count = Number(header.pointCount);
  const view = Las.View.create(bytes.slice(start, start + count * header.pointDataRecordLength),
                               header, eb);
  const names = ['X', 'Y', 'Z', 'Intensity', 'GpsTime', 'UserData', 'ReturnNumber',
                 'NumberOfReturns', 'Classification', 'PointSourceId', ...eb.map((e) => e.name)];
  for (const name of names) {
    const getter = view.getter(name);
    const values = new Array(view.pointCount);
    for (let i = 0; i < view.pointCount; ++i) values[i] = num(getter(i));
    out.points[name] = values;
  }
  return out;
}

const files = [];
for (const path of process.argv.slice(2)) {
  const bytes = bufferOf(path);
  files.push({ path, loaders: await readWithLoaders(bytes), copc: await readWithCopc(bytes) });
}
process.stdout.write(JSON.stringify({ files }) + '\n');
