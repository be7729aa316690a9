// Writes the mesh exported by an npm mesh package (`positions`, `cells`) as an OBJ file.
//     node npm_to_obj.cjs ./package/index.js out.obj
const [entry, out] = process.argv.slice(2);
const mesh = require(entry);
const vertices = mesh.positions.map((p) => `v ${p[0]} ${p[1]} ${p[2]}`);
const faces = mesh.cells.map((c) => "f " + c.map((i) => i + 1).join(" "));
require("fs").writeFileSync(out, vertices.concat(faces).join("\n") + "\n");
console.log(out, mesh.positions.length, "vertices", mesh.cells.length, "faces");
