//! No reader panics on any byte sequence: random bytes and mutated valid files (bit flips,
//! truncation, inserted bytes) are fed to every reader, as mesh and as point cloud. A panic
//! (or an abort from a huge allocation) fails the test; errors are the expected outcome.

// Test code: a panic in a helper is a failed test, as in the test functions.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use meshgnn_geometry::{
    MeshFormat, PlyEncoding, icosphere, read_mesh_bytes, read_point_cloud_bytes, write_mesh,
    write_ply,
};
use proptest::prelude::*;
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
        out
    })
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
}

#[test]
fn seeds_are_valid_so_mutations_start_from_real_files() {
    for (format, bytes) in seeds() {
        assert!(read_mesh_bytes(bytes, *format).is_ok(), "{format:?}");
    }
}
