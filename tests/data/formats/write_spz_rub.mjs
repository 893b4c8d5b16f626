// Write an SPZ the way Niantic's own PLY -> SPZ tools do: with the official spz library
// (the WebAssembly build @adobe/spz, which splat-transform bundles) converting from RDF
// (the 3DGS PLY convention) to SPZ's internal RUB, i.e. y and z negated on disk.
// (splat-transform itself writes from: UNSPECIFIED, i.e. PLY values as they are.)
//
//   node write_spz_rub.mjs IN.ply OUT.spz VERSION [DECODED_PREFIX]
//
// IN.ply: float-only binary little-endian PLY with x y z f_dc_0..2 opacity scale_0..2
// rot_0..3 (SH degree 0).  With DECODED_PREFIX, the file is read back with the same
// library (to: RDF and to: UNSPECIFIED) into DECODED_PREFIX.adobe_to_rdf.ply and
// DECODED_PREFIX.adobe_raw.ply.  Node resolves `@adobe/spz` from the script's own
// folder, so run a copy placed beside the node_modules that holds it (make.sh copies it
// into the splat-transform install folder; @adobe/spz 0.2.3 comes with splat-transform).
import fs from 'node:fs';
import createSpzModule from '@adobe/spz';
const [,, inPly, outSpz, version, prefix] = process.argv;
const buf = fs.readFileSync(inPly);
const end = buf.indexOf('end_header\n') + 'end_header\n'.length;
const header = buf.subarray(0, end).toString('ascii');
const n = parseInt(/element vertex (\d+)/.exec(header)[1]);
const props = [...header.matchAll(/property float (\S+)/g)].map(m => m[1]);
const w = props.length;
const f = new Float32Array(buf.buffer.slice(buf.byteOffset + end, buf.byteOffset + end + 4 * w * n));
const col = (name) => { const c = props.indexOf(name); const o = new Float32Array(n); for (let i = 0; i < n; i++) o[i] = f[i * w + c]; return o; };
const X = ['x','y','z'].map(col), S = ['scale_0','scale_1','scale_2'].map(col), C = ['f_dc_0','f_dc_1','f_dc_2'].map(col);
const A = col('opacity'), R = ['rot_1','rot_2','rot_3','rot_0'].map(col);   // spz: x y z w
const inter = (cols) => { const k = cols.length, o = new Float32Array(n * k); for (let i = 0; i < n; i++) for (let j = 0; j < k; j++) o[i * k + j] = cols[j][i]; return o; };
const spz = await createSpzModule();
const cloud = { numPoints: n, shDegree: 0, antialiased: false, extensions: [], positions: inter(X), scales: inter(S), rotations: inter(R), alphas: A, colors: inter(C), sh: new Float32Array(0) };
const bytes = spz.saveSpzToBuffer(cloud, { version: +version, from: spz.CoordinateSystem.RDF, sh1Bits: 5, shRestBits: 4 });
fs.writeFileSync(outSpz, bytes);
if (prefix) for (const [tag, to] of [['to_rdf', spz.CoordinateSystem.RDF], ['raw', spz.CoordinateSystem.UNSPECIFIED]]) {
  const c = spz.loadSpzFromBuffer(new Uint8Array(bytes), { to });
  const names = ['x','y','z','rot_0','rot_1','rot_2','rot_3','scale_0','scale_1','scale_2','opacity','f_dc_0','f_dc_1','f_dc_2'];
  const out = new Float32Array(n * 14);
  for (let i = 0; i < n; i++) {
    const p = c.positions, r = c.rotations, s = c.scales, cc = c.colors;
    out.set([p[3*i], p[3*i+1], p[3*i+2], r[4*i+3], r[4*i], r[4*i+1], r[4*i+2], s[3*i], s[3*i+1], s[3*i+2], c.alphas[i], cc[3*i], cc[3*i+1], cc[3*i+2]], i * 14);
  }
  const hdr = 'ply\nformat binary_little_endian 1.0\nelement vertex ' + n + '\n' + names.map(x => 'property float ' + x + '\n').join('') + 'end_header\n';
  fs.writeFileSync(prefix + '.adobe_' + tag + '.ply', Buffer.concat([Buffer.from(hdr), Buffer.from(out.buffer)]));
}
console.log('wrote', outSpz, bytes.length, 'bytes');
