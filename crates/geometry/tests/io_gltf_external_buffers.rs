//! glTF buffers that name other files: only regular files inside the glTF file's own folder
//! are read, never more than their declared `byteLength`; everything else is refused with a
//! one-line error naming the glTF file and the URI, without opening the target.

// Test code: a panic in a helper is a failed test, as in the test functions.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use meshgnn_geometry::{Error, MeshFormat, read_mesh, read_mesh_bytes, read_point_cloud};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// One triangle: 3 f32 positions (36 bytes) then u16 indices 0 1 2 (6 bytes), padded to 44.
fn triangle_bin() -> Vec<u8> {
    let mut bytes = Vec::new();
    for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        p.iter().for_each(|x| bytes.extend(x.to_le_bytes()));
    }
    [0u16, 1, 2]
        .iter()
        .for_each(|i| bytes.extend(i.to_le_bytes()));
    bytes.extend([0, 0]);
    bytes
}

/// A glTF document drawing the triangle from buffer 0 (`uri`, `byteLength`), instanced by a
/// binary tree of nodes `levels` deep (`2^levels` copies; 0: one node).
fn document(uri: Option<&str>, byte_length: usize, levels: usize) -> String {
    let uri = uri.map_or(String::new(), |u| format!(r#","uri":"{u}""#));
    let nodes: Vec<String> = (0..levels)
        .map(|i| format!(r#"{{"children":[{0},{0}]}}"#, i + 1))
        .chain([r#"{"mesh":0}"#.to_string()])
        .collect();
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
        "nodes":[{}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
        "buffers":[{{"byteLength":{byte_length}{uri}}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},
                       {{"buffer":0,"byteOffset":36,"byteLength":6}}],
        "accessors":[
          {{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
          {{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}]}}"#,
        nodes.join(",")
    )
}

/// A GLB container holding `json` and, when given, a binary chunk.
fn glb(json: &str, bin: Option<&[u8]>) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + bin.map_or(0, |b| 8 + b.len());
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(0x4E4F_534Au32.to_le_bytes());
    out.extend(json);
    if let Some(bin) = bin {
        out.extend((bin.len() as u32).to_le_bytes());
        out.extend(0x004E_4942u32.to_le_bytes());
        out.extend(bin);
    }
    out
}

/// `outer/` holds a secret (a valid buffer, so only the rules can stop it being read);
/// `outer/inner/` is the glTF file's folder.
struct Folders {
    _outer: tempfile::TempDir,
    outer: PathBuf,
    inner: PathBuf,
}

fn folders() -> Folders {
    let outer_dir = tempfile::tempdir().unwrap();
    let outer = outer_dir.path().to_path_buf();
    let inner = outer.join("inner");
    std::fs::create_dir(&inner).unwrap();
    std::fs::write(outer.join("secret.bin"), triangle_bin()).unwrap();
    Folders {
        _outer: outer_dir,
        outer,
        inner,
    }
}

/// Writes `m.gltf` into `folder` and reads it.
fn read_gltf_with(folder: &Path, json: &str) -> (PathBuf, meshgnn_geometry::Result<usize>) {
    let path = folder.join("m.gltf");
    std::fs::write(&path, json).unwrap();
    let result = read_mesh(&path).map(|m| m.vertex_count());
    (path, result)
}

/// The error is one line, names the glTF file and the URI, and says `expected`.
fn assert_refused(result: meshgnn_geometry::Result<usize>, file: &Path, uri: &str, expected: &str) {
    let message = match result {
        Err(e @ Error::Format { .. }) => e.to_string(),
        other => panic!("{uri}: expected a format error, got {other:?}"),
    };
    assert!(!message.contains('\n'), "{message}");
    assert!(message.contains(&file.display().to_string()), "{message}");
    assert!(message.contains(&format!("{uri:?}")), "{message}");
    assert!(message.contains(expected), "{uri}: {message}");
}

#[test]
fn a_sibling_bin_loads_also_through_subfolders_and_escapes() {
    let f = folders();
    std::fs::write(f.inner.join("tri.bin"), triangle_bin()).unwrap();
    std::fs::create_dir(f.inner.join("sub")).unwrap();
    std::fs::write(f.inner.join("sub").join("my tri.bin"), triangle_bin()).unwrap();
    for uri in [
        "tri.bin",
        "./tri.bin",
        "sub/my%20tri.bin",
        "sub/../tri.bin",
        "%74ri.bin",
    ] {
        let path = f.inner.join("m.gltf");
        std::fs::write(&path, document(Some(uri), 44, 0)).unwrap();
        let mesh = read_mesh(&path).unwrap_or_else(|e| panic!("{uri}: {e}"));
        assert_eq!(
            mesh.vertices(),
            &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
        );
        assert_eq!(mesh.triangles(), &[[0, 1, 2]]);
        assert_eq!(read_point_cloud(&path).unwrap().len(), 3);
    }
}

#[test]
fn external_buffers_from_memory_are_refused() {
    let result = read_mesh_bytes(
        document(Some("tri.bin"), 44, 0).as_bytes(),
        MeshFormat::Gltf,
    );
    match result {
        Err(e) => {
            let message = e.to_string();
            assert!(message.starts_with("<memory>:"), "{message}");
            assert!(message.contains(r#""tri.bin""#), "{message}");
            assert!(message.contains("from memory have no folder"), "{message}");
        }
        Ok(_) => panic!("external buffer read from memory"),
    }
}

#[test]
fn absolute_paths_and_schemes_are_refused() {
    let f = folders();
    let secret = f.outer.join("secret.bin").display().to_string();
    for (uri, expected) in [
        ("/etc/passwd", "absolute path"),
        ("%2Fetc%2Fpasswd", "absolute path"),
        (secret.as_str(), "absolute path"),
        (
            "file:///etc/passwd",
            "only data URIs and relative file references",
        ),
        (
            "http://example.com/a.bin",
            "only data URIs and relative file references",
        ),
        (
            "C:/Windows/win.ini",
            "only data URIs and relative file references",
        ),
        ("..%5Csecret.bin", "backslash"),
        ("tri.bin?x=1", "query or fragment"),
        ("%zz.bin", "invalid %-escape"),
        ("", "empty URI"),
    ] {
        let (path, result) = read_gltf_with(&f.inner, &document(Some(uri), 36, 0));
        assert_refused(result, &path, uri, expected);
    }
}

#[test]
fn climbing_out_with_dot_dot_is_refused_whether_or_not_the_target_exists() {
    let f = folders();
    std::fs::create_dir(f.inner.join("sub")).unwrap();
    for uri in [
        "../secret.bin",
        "sub/../../secret.bin",
        "..%2Fsecret.bin",
        "../missing.bin",
        "./../inner/../secret.bin",
    ] {
        let (path, result) = read_gltf_with(&f.inner, &document(Some(uri), 44, 0));
        assert_refused(result, &path, uri, "climbs out of the glTF file's folder");
    }
}

#[cfg(unix)]
#[test]
fn symlinks_inside_the_folder_that_point_outside_are_refused() {
    use std::os::unix::fs::symlink;
    let f = folders();
    symlink(f.outer.join("secret.bin"), f.inner.join("link.bin")).unwrap();
    symlink(&f.outer, f.inner.join("up")).unwrap();
    // A symlink that stays inside is fine.
    std::fs::write(f.inner.join("tri.bin"), triangle_bin()).unwrap();
    symlink(f.inner.join("tri.bin"), f.inner.join("alias.bin")).unwrap();
    for uri in ["link.bin", "up/secret.bin", "up/inner/../secret.bin"] {
        let (path, result) = read_gltf_with(&f.inner, &document(Some(uri), 44, 0));
        assert_refused(result, &path, uri, "outside the glTF file's folder");
    }
    let (_, result) = read_gltf_with(&f.inner, &document(Some("alias.bin"), 44, 0));
    assert_eq!(result.unwrap(), 3);
}

#[cfg(unix)]
#[test]
fn devices_are_refused_without_reading() {
    use std::os::unix::fs::symlink;
    let f = folders();
    // Declared a terabyte: had anything been read, the test would run out of memory.
    let huge = 1usize << 40;
    for device in ["/dev/zero", "/dev/urandom"] {
        let (path, result) = read_gltf_with(&f.inner, &document(Some(device), huge, 0));
        assert_refused(result, &path, device, "absolute path");
        let name = device.trim_start_matches("/dev/");
        symlink(device, f.inner.join(name)).unwrap();
        let (path, result) = read_gltf_with(&f.inner, &document(Some(name), huge, 0));
        assert_refused(result, &path, name, "outside the glTF file's folder");
    }
}

#[test]
fn a_directory_is_refused() {
    let f = folders();
    std::fs::create_dir(f.inner.join("data.bin")).unwrap();
    let (path, result) = read_gltf_with(&f.inner, &document(Some("data.bin"), 44, 0));
    assert_refused(result, &path, "data.bin", "a directory, not a regular file");
}

#[cfg(unix)]
#[test]
fn a_fifo_is_refused_without_blocking() {
    let f = folders();
    let fifo = f.inner.join("pipe.bin");
    match std::process::Command::new("mkfifo").arg(&fifo).status() {
        Ok(status) if status.success() => {}
        other => {
            eprintln!("skipped: mkfifo unavailable ({other:?})");
            return;
        }
    }
    let folder = f.inner.clone();
    let (send, receive) = std::sync::mpsc::channel();
    // A reader that opened the FIFO would block forever: run it on a thread and time out.
    std::thread::spawn(move || {
        let _ = send.send(read_gltf_with(&folder, &document(Some("pipe.bin"), 44, 0)));
    });
    let (path, result) = receive
        .recv_timeout(Duration::from_secs(30))
        .expect("reading a glTF whose buffer is a FIFO blocked");
    assert_refused(result, &path, "pipe.bin", "not a regular file");
}

#[test]
fn byte_length_is_checked_against_the_file_before_reading_and_bounds_the_read() {
    let f = folders();
    // The file is shorter than declared: refused.
    std::fs::write(f.inner.join("short.bin"), &triangle_bin()[..40]).unwrap();
    let (path, result) = read_gltf_with(&f.inner, &document(Some("short.bin"), 44, 0));
    assert_refused(
        result,
        &path,
        "short.bin",
        "declares byteLength 44, the file has 40 bytes",
    );
    // The file is longer (padding): only byteLength bytes count.
    let mut long = triangle_bin();
    long.extend([7u8; 1000]);
    std::fs::write(f.inner.join("long.bin"), &long).unwrap();
    let (_, result) = read_gltf_with(&f.inner, &document(Some("long.bin"), 44, 0));
    assert_eq!(result.unwrap(), 3);
    // Declared 40: the index view (bytes 36..42) is past the buffer even though the file
    // holds it, so the bytes beyond byteLength were not used.
    let (_, result) = read_gltf_with(&f.inner, &document(Some("long.bin"), 40, 0));
    match result {
        Err(Error::Format { message, .. }) => {
            assert!(message.contains("runs past buffer 0"), "{message}")
        }
        other => panic!("expected an error, got {other:?}"),
    }
}

#[test]
fn glb_buffers_follow_the_same_rules() {
    let f = folders();
    let write_glb = |json: &str, bin: Option<&[u8]>| {
        let path = f.inner.join("m.glb");
        std::fs::write(&path, glb(json, bin)).unwrap();
        (path.clone(), read_mesh(&path).map(|m| m.vertex_count()))
    };
    for (uri, expected) in [
        ("../secret.bin", "climbs out"),
        ("/etc/passwd", "absolute path"),
    ] {
        let (path, result) = write_glb(&document(Some(uri), 44, 0), None);
        assert_refused(result, &path, uri, expected);
    }
    // A GLB whose buffer is a sibling file, and one with its own binary chunk.
    std::fs::write(f.inner.join("tri.bin"), triangle_bin()).unwrap();
    let (_, result) = write_glb(&document(Some("tri.bin"), 44, 0), None);
    assert_eq!(result.unwrap(), 3);
    let (_, result) = write_glb(&document(None, 44, 0), Some(&triangle_bin()));
    assert_eq!(result.unwrap(), 3);
    // The chunk shorter than declared, and no chunk at all.
    let (path, result) = write_glb(&document(None, 48, 0), Some(&triangle_bin()));
    assert!(matches!(result, Err(Error::Format { .. })), "{path:?}");
    let (_, result) = write_glb(&document(None, 44, 0), None);
    match result {
        Err(e) => assert!(e.to_string().contains("no GLB binary chunk"), "{e}"),
        Ok(_) => panic!("a buffer without uri or chunk was read"),
    }
}

#[test]
fn data_uris_are_bounded_by_their_declared_length() {
    let f = folders();
    // "AAAA" decodes to 3 bytes; the buffer declares 44.
    let uri = "data:application/octet-stream;base64,AAAA";
    let (path, result) = read_gltf_with(&f.inner, &document(Some(uri), 44, 0));
    assert_refused(
        result,
        &path,
        uri,
        "declares byteLength 44, the data URI holds at most 5 bytes",
    );
    // A terabyte declared in a short URI is refused before decoding.
    let (path, result) = read_gltf_with(&f.inner, &document(Some(uri), 1 << 40, 0));
    assert_refused(result, &path, uri, "above the data URI limit");
    let uri = "data:application/octet-stream,plain";
    let (path, result) = read_gltf_with(&f.inner, &document(Some(uri), 5, 0));
    assert_refused(result, &path, uri, "only base64 data URIs");
}

#[test]
fn instancing_cannot_expand_a_small_file_without_bound() {
    let f = folders();
    std::fs::write(f.inner.join("tri.bin"), triangle_bin()).unwrap();
    // Two copies of the triangle are fine.
    let (_, result) = read_gltf_with(&f.inner, &document(Some("tri.bin"), 44, 1));
    assert_eq!(result.unwrap(), 6);
    // 2^15 copies of a 44-byte buffer would read 6 elements each: refused at 704.
    let (_, result) = read_gltf_with(&f.inner, &document(Some("tri.bin"), 44, 15));
    match result {
        Err(Error::Format { message, .. }) => {
            assert!(message.contains("over 704 elements"), "{message}")
        }
        other => panic!("expected an error, got {other:?}"),
    }
}
