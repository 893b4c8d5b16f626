// Reads a glTF with the generic glTF library @gltf-transform/core and writes it again (its
// own buffer layout), carrying KHR_gaussian_splatting through: the library does not know
// the extension, so the primitive's extension object is kept aside on read and put back on
// write. Attributes (KHR_gaussian_splatting:*, _SPLATTER_LABEL) and extras pass as they are.
//
//   node gs_passthrough.mjs IN.glb OUT.glb
import { Extension, NodeIO } from '@gltf-transform/core';

const NAME = 'KHR_gaussian_splatting';
const KEPT = '__khr_gaussian_splatting';

class GaussianSplatting extends Extension {
    static EXTENSION_NAME = NAME;
    extensionName = NAME;

    read(context) {
        const meshes = context.jsonDoc.json.meshes || [];
        meshes.forEach((mesh, m) => {
            const prims = context.meshes[m].listPrimitives();
            mesh.primitives.forEach((p, i) => {
                const ext = p.extensions && p.extensions[NAME];
                if (ext) prims[i].setExtras({ ...prims[i].getExtras(), [KEPT]: ext });
            });
        });
        return this;
    }

    write(context) {
        for (const mesh of context.jsonDoc.json.meshes || []) {
            for (const p of mesh.primitives) {
                if (p.extras && p.extras[KEPT]) {
                    p.extensions = { ...(p.extensions || {}), [NAME]: p.extras[KEPT] };
                    delete p.extras[KEPT];
                    if (Object.keys(p.extras).length === 0) delete p.extras;
                }
            }
        }
        return this;
    }
}

const [input, output] = process.argv.slice(2);
const io = new NodeIO().registerExtensions([GaussianSplatting]);
const doc = await io.read(input);
doc.createExtension(GaussianSplatting);
await io.write(output, doc);
