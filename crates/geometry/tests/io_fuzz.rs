//! No reader panics on any byte sequence: random bytes and mutated valid files (bit flips,
//! truncation, inserted bytes) are fed to every reader, as mesh and as point cloud. A panic
//! (or an abort from a huge allocation) fails the test; errors are the expected outcome.
//! glTF files are also read from a folder whose neighbours include a symlink out of it, a
//! device link and a FIFO: whatever the URIs say, nothing outside the folder comes back.
//! The same cases run for longer under cargo-fuzz (`fuzz/`, see docs/security.md).

// Test code: a panic in a helper is a failed test, as in the test functions.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use meshgnn_geometry::{
    MeshFormat, PlyEncoding, icosphere, read_mesh, read_mesh_bytes, read_point_cloud,
    read_point_cloud_bytes, write_mesh, write_ply,
};
use proptest::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Valid seed files, written once by our writers (plus hand-written headers).
fn seeds() -> &'static Vec<(MeshFormat, Vec<u8>)> {
    static SEEDS: OnceLock<Vec<(MeshFormat, Vec<u8>)>> = OnceLock::new();
    SEEDS.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        let sphere = icosphere(1);
        let normals = sphere.vertices().to_vec();
        let uvs = normals.iter().map(|n| [n[0], n[1]]).collect();
        let mesh = sphere.with_normals(normals).unwrap().with_uvs(uvs).unwrap();
        let mut out = Vec::new();
        for encoding in [
            PlyEncoding::Ascii,
            PlyEncoding::BinaryLittleEndian,
            PlyEncoding::BinaryBigEndian,
        ] {
            let path = dir.path().join("m.ply");
            write_ply(&path, &mesh, encoding).unwrap();
            out.push((MeshFormat::Ply, std::fs::read(&path).unwrap()));
        }
        for (ext, format) in [
            ("obj", MeshFormat::Obj),
            ("off", MeshFormat::Off),
            ("glb", MeshFormat::Glb),
            ("xyz", MeshFormat::Xyz),
        ] {
            let path = dir.path().join(format!("m.{ext}"));
            write_mesh(&path, &mesh).unwrap();
            out.push((format, std::fs::read(&path).unwrap()));
        }
        // A general-layout PLY: skipped list element, double coordinates, ushort lists.
        let mut general = b"ply\nformat binary_little_endian 1.0\nelement junk 2\n\
            property list uchar int data\nelement vertex 3\nproperty double x\n\
            property double y\nproperty double z\nproperty uchar red\nproperty uchar green\n\
            property uchar blue\nelement face 1\nproperty list ushort uint vertex_index\n\
            end_header\n"
            .to_vec();
        general.extend([1, 7, 0, 0, 0, 0]);
        for i in 0..3u8 {
            for c in 0..3 {
                general.extend(f64::from(i + c).to_le_bytes());
            }
            general.extend([i, 2 * i, 3 * i]);
        }
        general.extend(3u16.to_le_bytes());
        [0u32, 1, 2]
            .iter()
            .for_each(|i| general.extend(i.to_le_bytes()));
        out.push((MeshFormat::Ply, general));
        let data_uri = format!(
            "data:application/octet-stream;base64,{}",
            base64(&triangle_bin(None))
        );
        out.push((
            MeshFormat::Gltf,
            gltf_document(&data_uri, 44, 1).into_bytes(),
        ));
        out
    })
}

/// A triangle buffer: 3 f32 positions (all equal to `x` when given, else 0 0 0, 1 0 0,
/// 0 1 0), u16 indices 0 1 2, padded to 44 bytes.
fn triangle_bin(x: Option<f32>) -> Vec<u8> {
    let mut bytes = Vec::new();
    for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        p.iter()
            .for_each(|&c| bytes.extend(x.unwrap_or(c).to_le_bytes()));
    }
    [0u16, 1, 2]
        .iter()
        .for_each(|i| bytes.extend(i.to_le_bytes()));
    bytes.extend([0, 0]);
    bytes
}

fn base64(bytes: &[u8]) -> String {
    const TABLE: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [0, 1, 2].map(|i| chunk.get(i).copied().unwrap_or(0));
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for i in 0..4 {
            out.push(if i <= chunk.len() {
                TABLE[((n >> (18 - 6 * i)) & 63) as usize] as char
            } else {
                '='
            });
        }
    }
    out
}

/// A glTF document drawing the triangle from one buffer (`uri`, `byte_length`), placed by
/// `instances` nodes.
fn gltf_document(uri: &str, byte_length: u64, instances: usize) -> String {
    let nodes = vec![r#"{"mesh":0}"#; instances].join(",");
    let roots: Vec<String> = (0..instances).map(|i| i.to_string()).collect();
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[{}]}}],"nodes":[{nodes}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
        "buffers":[{{"byteLength":{byte_length},"uri":"{uri}"}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},
                       {{"buffer":0,"byteOffset":36,"byteLength":6}}],
        "accessors":[
          {{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
          {{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}]}}"#,
        roots.join(",")
    )
}

/// The coordinate of the buffer outside the folder: seeing it in a result means it was read.
const SECRET: f32 = 31337.0;

/// `root/inner/` holds `tri.bin` (a valid buffer), `sub/tri.bin`, `dir.bin/`, symlinks out
/// (`link.bin` → `../secret.bin`, `up` → `root`), `zero` → `/dev/zero` and a FIFO `pipe.bin`
/// (where `mkfifo` exists; a reader that opened it would hang the test).
fn folder() -> &'static Path {
    static FOLDER: OnceLock<(tempfile::TempDir, PathBuf)> = OnceLock::new();
    let (_, inner) = FOLDER.get_or_init(|| {
        let root = tempfile::tempdir().unwrap();
        let inner = root.path().join("inner");
        std::fs::create_dir_all(inner.join("sub")).unwrap();
        std::fs::create_dir(inner.join("dir.bin")).unwrap();
        std::fs::write(root.path().join("secret.bin"), triangle_bin(Some(SECRET))).unwrap();
        std::fs::write(inner.join("tri.bin"), triangle_bin(None)).unwrap();
        std::fs::write(inner.join("sub").join("tri.bin"), triangle_bin(None)).unwrap();
        #[cfg(unix)]
        {
            use std::os::unix::fs::symlink;
            symlink(root.path().join("secret.bin"), inner.join("link.bin")).unwrap();
            symlink(root.path(), inner.join("up")).unwrap();
            symlink("/dev/zero", inner.join("zero")).unwrap();
            let _ = std::process::Command::new("mkfifo")
                .arg(inner.join("pipe.bin"))
                .status();
        }
        (root, inner)
    });
    inner
}

/// URIs a hostile or careless file may hold, legitimate ones among them.
const URIS: [&str; 16] = [
    "tri.bin",
    "sub/tri.bin",
    "sub/../tri.bin",
    "%74ri.bin",
    "../secret.bin",
    "sub/../../secret.bin",
    "..%2Fsecret.bin",
    "link.bin",
    "up/secret.bin",
    "up/inner/tri.bin",
    "zero",
    "pipe.bin",
    "dir.bin",
    "/dev/zero",
    "/etc/passwd",
    "file:///etc/passwd",
];

/// Writes `bytes` as `name` into [`folder`] and reads it both ways; the only failure is a
/// panic or a result holding the outside buffer's coordinate.
fn read_in_folder(bytes: &[u8], name: &str) {
    let path = folder().join(name);
    std::fs::write(&path, bytes).unwrap();
    if let Ok(mesh) = read_mesh(&path) {
        assert!(!mesh.vertices().iter().flatten().any(|&x| x == SECRET));
    }
    if let Ok(cloud) = read_point_cloud(&path) {
        assert!(!cloud.points().iter().flatten().any(|&x| x == SECRET));
    }
}

/// `json` in a GLB container without a binary chunk.
fn glb_container(json: &str) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((20 + json.len()) as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(0x4E4F_534Au32.to_le_bytes());
    out.extend(json);
    out
}

/// Runs every reader that can take `format` on `bytes`; only a panic fails.
fn exercise(bytes: &[u8], format: MeshFormat) {
    let _ = read_mesh_bytes(bytes, format);
    let _ = read_point_cloud_bytes(bytes, format);
    if format == MeshFormat::Glb {
        let _ = read_mesh_bytes(bytes, MeshFormat::Gltf);
    }
}

#[derive(Debug, Clone)]
enum Mutation {
    FlipBit(usize, u8),
    Truncate(usize),
    Insert(usize, Vec<u8>),
    Overwrite(usize, u8),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), 0u8..8).prop_map(|(i, b)| Mutation::FlipBit(i, b)),
        any::<usize>().prop_map(Mutation::Truncate),
        (any::<usize>(), prop::collection::vec(any::<u8>(), 1..8))
            .prop_map(|(i, b)| Mutation::Insert(i, b)),
        (
            any::<usize>(),
            prop::sample::select(vec![
                b'0', b'9', b'-', b' ', b'\n', b'.', b'e', b'/', 0, 255, 3, b'#'
            ])
        )
            .prop_map(|(i, b)| Mutation::Overwrite(i, b)),
    ]
}

fn mutate(bytes: &mut Vec<u8>, mutations: &[Mutation]) {
    for m in mutations {
        if bytes.is_empty() {
            return;
        }
        let len = bytes.len();
        match m {
            Mutation::FlipBit(i, b) => bytes[i % len] ^= 1 << b,
            Mutation::Truncate(i) => bytes.truncate(i % len),
            Mutation::Insert(i, b) => {
                let at = i % len;
                bytes.splice(at..at, b.iter().copied());
            }
            Mutation::Overwrite(i, b) => bytes[i % len] = *b,
        }
    }
}

const FORMATS: [MeshFormat; 6] = [
    MeshFormat::Ply,
    MeshFormat::Obj,
    MeshFormat::Off,
    MeshFormat::Glb,
    MeshFormat::Gltf,
    MeshFormat::Xyz,
];

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn random_bytes_never_panic(
        bytes in prop::collection::vec(any::<u8>(), 0..512),
        format in prop::sample::select(FORMATS.to_vec()),
    ) {
        exercise(&bytes, format);
    }

    #[test]
    fn random_text_after_a_valid_header_never_panics(
        body in "[0-9 .e+\\-\n/#nafi]{0,300}",
        header in prop::sample::select(vec![
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
             property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n",
            "OFF\n3 2 0\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\n",
            "",
        ]),
    ) {
        let text = format!("{header}{body}");
        for format in [MeshFormat::Ply, MeshFormat::Off, MeshFormat::Obj, MeshFormat::Xyz] {
            exercise(text.as_bytes(), format);
        }
    }

    #[test]
    fn random_binary_after_a_valid_ply_header_never_panics(
        body in prop::collection::vec(any::<u8>(), 0..400),
        big_endian in any::<bool>(),
    ) {
        let mut bytes = format!(
            "ply\nformat binary_{}_endian 1.0\nelement vertex 3\nproperty float x\n\
             property float y\nproperty float z\nelement face 2\n\
             property list uchar int vertex_indices\nend_header\n",
            if big_endian { "big" } else { "little" }
        )
        .into_bytes();
        bytes.extend(body);
        exercise(&bytes, MeshFormat::Ply);
    }
}

/// One mutation test per seed file (each reader and PLY encoding), 256 cases each.
macro_rules! mutated_seed_tests {
    ($($name:ident => $index:expr),* $(,)?) => {
        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]
            $(
                #[test]
                fn $name(mutations in prop::collection::vec(mutation(), 1..6)) {
                    let (format, seed) = &seeds()[$index];
                    let mut bytes = seed.clone();
                    mutate(&mut bytes, &mutations);
                    exercise(&bytes, *format);
                }
            )*
        }
    };
}

mutated_seed_tests! {
    mutated_ply_ascii_never_panics => 0,
    mutated_ply_binary_little_endian_never_panics => 1,
    mutated_ply_binary_big_endian_never_panics => 2,
    mutated_obj_never_panics => 3,
    mutated_off_never_panics => 4,
    mutated_glb_never_panics => 5,
    mutated_xyz_never_panics => 6,
    mutated_ply_general_layout_never_panics => 7,
    mutated_gltf_data_uri_never_panics => 8,
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Every URI rule, as `.gltf` and inside a `.glb`, with declared lengths around the real
    /// 44 bytes and far beyond, then mutated: nothing outside the folder is ever read.
    #[test]
    fn gltf_in_a_folder_never_reads_outside_it(
        uri in prop::sample::select(URIS.to_vec()),
        byte_length in prop::sample::select(vec![0u64, 36, 43, 44, 45, 1 << 20, 1 << 40]),
        instances in 1usize..4,
        mutations in prop::collection::vec(mutation(), 0..3),
        as_glb in any::<bool>(),
    ) {
        let json = gltf_document(uri, byte_length, instances);
        let (mut bytes, name) = if as_glb {
            (glb_container(&json), "proptest.glb")
        } else {
            (json.into_bytes(), "proptest.gltf")
        };
        mutate(&mut bytes, &mutations);
        read_in_folder(&bytes, name);
    }
}

#[test]
fn only_the_uris_inside_the_folder_load() {
    for uri in URIS {
        let json = gltf_document(uri, 44, 1);
        // File names distinct from the proptest's: tests share the folder and run in parallel.
        let path = folder().join("uris.gltf");
        std::fs::write(&path, &json).unwrap();
        let inside = matches!(
            uri,
            "tri.bin" | "sub/tri.bin" | "sub/../tri.bin" | "%74ri.bin" | "up/inner/tri.bin"
        );
        assert_eq!(read_mesh(&path).is_ok(), inside, "{uri}");
        read_in_folder(&glb_container(&json), "uris.glb");
    }
}

#[test]
fn seeds_are_valid_so_mutations_start_from_real_files() {
    for (format, bytes) in seeds() {
        assert!(read_mesh_bytes(bytes, *format).is_ok(), "{format:?}");
    }
}
