//! [`GltfBuffers`]: the bytes behind each `buffers[i]` of a glTF document, resolved under
//! rules that make a hostile file harmless.
//!
//! A glTF buffer (glTF 2.0 specification, §3.6.1 "Buffers and Buffer Views") is the GLB
//! binary chunk, a `data:` URI, or a URI naming another file. A file from the internet can
//! name `/etc/passwd`, `../../.ssh/id_rsa`, `/dev/zero` or a FIFO; following such a URI leaks
//! the machine's files, exhausts memory or blocks forever. So:
//!
//! - **External files**: only a relative reference (no scheme, no leading `/`, no `\`, no
//!   `?` or `#`), percent-decoded, that names a *regular file* inside the glTF file's own
//!   folder after canonicalisation (`..` and symlinks resolved: a link inside the folder that
//!   points outside is refused). The file's length is checked against the declared
//!   `byteLength` before reading (shorter: refused, as the specification requires the
//!   resource to hold `byteLength` bytes; longer: padding, only `byteLength` bytes are read),
//!   and the read itself is bounded (`take(byteLength)`), so a file growing under us cannot
//!   exceed it. A file named by several buffers is read once.
//! - **`data:` URIs**: base64 only, decoded size at least `byteLength` and at most
//!   [`MAX_DATA_URI_BYTES`], checked from the encoded length before decoding.
//! - **GLB binary chunk**: only buffer 0 may omit its URI (§4.4.3.3), and the chunk must hold
//!   its `byteLength`. A GLB's other buffers follow the rules above.
//! - Bytes from memory ([`crate::read_mesh_bytes`]) have no folder: external URIs are refused.
//!
//! Everything is checked for every buffer before any external file is opened, and each
//! refusal is one line naming the glTF file, the buffer and its URI. Memory is therefore
//! bounded by the glTF file plus the files it names in its own folder.
//!
//! A file swapped for a FIFO or a symbolic link between the check and the open cannot block or
//! redirect the read: the open is non-blocking and does not follow a link in the last
//! component, and the opened handle is checked again.

use super::format_error::format_error;
use super::uri_decoding::{base64_decode, base64_decoded_bound, percent_decode};
use crate::error::Result;
use gltf::buffer::Source;
use std::collections::HashMap;
use std::io::Read;
use std::path::{Path, PathBuf};

/// Largest buffer a `data:` URI may hold once decoded (1 GiB). The decoded bytes are also
/// bounded by the URI's own length, so this mostly says where embedding stops being
/// sensible: larger buffers belong in a `.bin` file or a GLB.
pub(crate) const MAX_DATA_URI_BYTES: usize = 1 << 30;

/// Where a buffer's bytes live.
#[derive(Debug, Clone, Copy)]
enum Origin {
    /// The GLB binary chunk.
    Chunk,
    /// `decoded[i]`: a decoded data URI.
    Data(usize),
    /// `files[i]`: an external file.
    File(usize),
}

/// The bytes of every buffer of one document, in document order; each buffer is exactly its
/// declared `byteLength` long.
#[derive(Debug)]
pub(crate) struct GltfBuffers<'a> {
    chunk: Option<&'a [u8]>,
    decoded: Vec<Vec<u8>>,
    files: Vec<Vec<u8>>,
    buffers: Vec<(Origin, usize)>,
}

/// An external file to read: its canonical path and the most bytes any buffer needs of it.
struct PendingFile {
    path: PathBuf,
    needed: usize,
}

impl<'a> GltfBuffers<'a> {
    /// Resolves every buffer of `document` read from `path`. `chunk` is the GLB binary chunk;
    /// `folder` the glTF file's folder (`None` for bytes from memory).
    pub(crate) fn load(
        document: &gltf::Document,
        chunk: Option<&'a [u8]>,
        path: &Path,
        folder: Option<&Path>,
    ) -> Result<Self> {
        let mut decoded = Vec::new();
        let mut buffers = Vec::new();
        let mut pending: Vec<PendingFile> = Vec::new();
        let mut file_slot: HashMap<PathBuf, usize> = HashMap::new();
        let mut canonical_folder = None;
        for buffer in document.buffers() {
            let (index, length) = (buffer.index(), buffer.length());
            let uri = match buffer.source() {
                Source::Bin => None,
                Source::Uri(uri) => Some(uri),
            };
            let refuse = |message: String| {
                let element = match uri {
                    Some(uri) => format!("buffer {index} (uri {})", shown(uri)),
                    None => format!("buffer {index} (GLB binary chunk)"),
                };
                format_error(path, element, message)
            };
            let origin = match uri {
                None => {
                    let chunk = chunk.ok_or_else(|| {
                        refuse("has no uri and the file has no GLB binary chunk".into())
                    })?;
                    if index != 0 {
                        return Err(refuse(
                            "has no uri; only buffer 0 may be the GLB binary chunk".into(),
                        ));
                    }
                    if chunk.len() < length {
                        return Err(refuse(format!(
                            "declares byteLength {length}, the chunk has {} bytes",
                            chunk.len()
                        )));
                    }
                    Origin::Chunk
                }
                Some(uri) if has_prefix_ignoring_case(uri, "data:") => {
                    decoded.push(decode_data_uri(uri, length).map_err(refuse)?);
                    Origin::Data(decoded.len() - 1)
                }
                Some(uri) => {
                    let folder = folder.ok_or_else(|| {
                        refuse("external file refused: bytes from memory have no folder".into())
                    })?;
                    if canonical_folder.is_none() {
                        canonical_folder = Some(canonical(folder).map_err(|e| {
                            refuse(format!("cannot resolve the glTF file's folder: {e}"))
                        })?);
                    }
                    let root = canonical_folder.as_deref().unwrap_or(folder);
                    let file = check_external(uri, root, length).map_err(refuse)?;
                    let slot = *file_slot.entry(file.clone()).or_insert_with(|| {
                        pending.push(PendingFile {
                            path: file,
                            needed: 0,
                        });
                        pending.len() - 1
                    });
                    if let Some(file) = pending.get_mut(slot) {
                        file.needed = file.needed.max(length);
                    }
                    Origin::File(slot)
                }
            };
            buffers.push((origin, length));
        }
        // Every buffer passed its checks: only now are the files opened.
        let files = pending
            .into_iter()
            .map(|file| {
                read_bounded(&file.path, file.needed).map_err(|message| {
                    format_error(
                        path,
                        format!("buffer file {}", file.path.display()),
                        message,
                    )
                })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Self {
            chunk,
            decoded,
            files,
            buffers,
        })
    }

    /// The bytes of buffer `index` (exactly its `byteLength`), `None` if there is no such
    /// buffer.
    pub(crate) fn get(&self, index: usize) -> Option<&[u8]> {
        let &(origin, length) = self.buffers.get(index)?;
        let bytes = match origin {
            Origin::Chunk => self.chunk?,
            Origin::Data(i) => self.decoded.get(i)?,
            Origin::File(i) => self.files.get(i)?,
        };
        bytes.get(..length)
    }

    /// Sum of the buffers' `byteLength`s: the data the document's accessors can draw on.
    pub(crate) fn total_len(&self) -> usize {
        self.buffers
            .iter()
            .fold(0usize, |sum, &(_, length)| sum.saturating_add(length))
    }
}

/// A URI as shown in errors: quoted, escaped onto one line, long ones (data URIs) cut.
fn shown(uri: &str) -> String {
    const SHOWN: usize = 64;
    match uri.char_indices().nth(SHOWN) {
        Some((cut, _)) => format!("{:?}...", &uri[..cut]),
        None => format!("{uri:?}"),
    }
}

fn has_prefix_ignoring_case(text: &str, prefix: &str) -> bool {
    text.get(..prefix.len())
        .is_some_and(|head| head.eq_ignore_ascii_case(prefix))
}

fn canonical(path: &Path) -> std::io::Result<PathBuf> {
    // A bare file name's parent is the empty path: the current folder.
    let path = if path.as_os_str().is_empty() {
        Path::new(".")
    } else {
        path
    };
    std::fs::canonicalize(path)
}

/// Decodes a base64 `data:[<media type>];base64,<payload>` URI into at least `length` bytes.
fn decode_data_uri(uri: &str, length: usize) -> std::result::Result<Vec<u8>, String> {
    let (header, payload) = uri
        .split_once(',')
        .ok_or_else(|| "data URI without a ',' before its payload".to_string())?;
    if !header.to_ascii_lowercase().ends_with(";base64") {
        return Err("only base64 data URIs are supported".into());
    }
    if length > MAX_DATA_URI_BYTES {
        return Err(format!(
            "declares byteLength {length}, above the data URI limit of {MAX_DATA_URI_BYTES} bytes"
        ));
    }
    let bound = base64_decoded_bound(payload.len());
    if bound < length {
        return Err(format!(
            "declares byteLength {length}, the data URI holds at most {bound} bytes"
        ));
    }
    if bound > MAX_DATA_URI_BYTES.saturating_add(2) {
        return Err(format!(
            "data URI of {} characters is above the limit of {MAX_DATA_URI_BYTES} decoded bytes",
            payload.len()
        ));
    }
    let bytes = base64_decode(payload).ok_or_else(|| "invalid base64 in data URI".to_string())?;
    if bytes.len() < length {
        return Err(format!(
            "declares byteLength {length}, the data URI decodes to {} bytes",
            bytes.len()
        ));
    }
    Ok(bytes)
}

/// The canonical path of the regular file `uri` names inside `folder` (already canonical),
/// holding at least `length` bytes; nothing is opened.
fn check_external(uri: &str, folder: &Path, length: usize) -> std::result::Result<PathBuf, String> {
    let relative = relative_path(uri)?;
    let target = std::fs::canonicalize(folder.join(&relative))
        .map_err(|e| format!("cannot resolve {}: {e}", relative.display()))?;
    if !target.starts_with(folder) {
        return Err(format!(
            "refused: resolves to {}, outside the glTF file's folder {}",
            target.display(),
            folder.display()
        ));
    }
    let metadata =
        std::fs::metadata(&target).map_err(|e| format!("cannot read {}: {e}", target.display()))?;
    check_regular(&metadata, length)?;
    Ok(target)
}

/// `uri` as a relative path, or why it is not a relative reference to a file.
fn relative_path(uri: &str) -> std::result::Result<PathBuf, String> {
    let scheme_end = uri.find(|c: char| !(c.is_ascii_alphanumeric() || "+-.".contains(c)));
    let starts_alpha = uri.starts_with(|c: char| c.is_ascii_alphabetic());
    if starts_alpha && scheme_end.is_some_and(|end| uri[end..].starts_with(':')) {
        return Err("refused: only data URIs and relative file references are allowed".into());
    }
    if uri.contains(['?', '#']) {
        return Err("refused: query or fragment in a file reference".into());
    }
    let decoded = percent_decode(uri).ok_or_else(|| "invalid %-escape".to_string())?;
    let decoded = String::from_utf8(decoded)
        .map_err(|_| "refused: the decoded path is not UTF-8".to_string())?;
    if decoded.is_empty() {
        return Err("empty URI".into());
    }
    if decoded.starts_with('/') {
        return Err("refused: absolute path".into());
    }
    if decoded.contains(['\\', '\0']) {
        return Err("refused: backslash or NUL in a file reference".into());
    }
    // `..` that climbs above the folder is refused before the file system is asked (which
    // would tell whether a file outside exists); symlinks are caught after canonicalisation.
    let mut depth = 0usize;
    for part in decoded.split('/') {
        match part {
            "" | "." => {}
            ".." => {
                depth = depth.checked_sub(1).ok_or_else(|| {
                    "refused: `..` climbs out of the glTF file's folder".to_string()
                })?;
            }
            _ => depth += 1,
        }
    }
    Ok(PathBuf::from(decoded))
}

/// Refuses anything but a regular file of at least `length` bytes.
fn check_regular(metadata: &std::fs::Metadata, length: usize) -> std::result::Result<(), String> {
    if metadata.is_dir() {
        return Err("refused: a directory, not a regular file".into());
    }
    if !metadata.is_file() {
        return Err("refused: not a regular file (a FIFO, device or socket)".into());
    }
    if metadata.len() < length as u64 {
        return Err(format!(
            "declares byteLength {length}, the file has {} bytes",
            metadata.len()
        ));
    }
    Ok(())
}

/// Opens the checked file at `path` so that a file swapped in since the check cannot block or
/// redirect the open: non-blocking (a FIFO opens at once and is then refused by the handle's
/// re-check) and not through a symbolic link in the last component (the checked path is
/// canonical, so a link there was put in after the check).
fn open_checked(path: &Path) -> std::io::Result<std::fs::File> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK | libc::O_NOFOLLOW);
    }
    options.open(path)
}

/// Reads the first `needed` bytes of the regular file at `path`, re-checking the opened
/// handle (the file may have changed since it was checked) and never reading more.
fn read_bounded(path: &Path, needed: usize) -> std::result::Result<Vec<u8>, String> {
    let file = open_checked(path).map_err(|e| e.to_string())?;
    let metadata = file.metadata().map_err(|e| e.to_string())?;
    check_regular(&metadata, needed)?;
    let mut bytes = Vec::with_capacity(needed);
    file.take(needed as u64)
        .read_to_end(&mut bytes)
        .map_err(|e| e.to_string())?;
    if bytes.len() < needed {
        return Err(format!(
            "file shrank while reading: {} of {needed} bytes",
            bytes.len()
        ));
    }
    Ok(bytes)
}

#[cfg(all(test, unix))]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use std::time::Duration;

    /// The read after the check, on files swapped in since: a FIFO neither blocks nor is read,
    /// a symbolic link (here to a valid file) is not followed.
    #[test]
    fn a_file_swapped_after_the_check_is_refused_without_blocking() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("swapped.bin");
        match std::process::Command::new("mkfifo").arg(&fifo).status() {
            Ok(status) if status.success() => {}
            other => {
                eprintln!("skipped: mkfifo unavailable ({other:?})");
                return;
            }
        }
        let (send, receive) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let _ = send.send(read_bounded(&fifo, 4));
        });
        let result = receive
            .recv_timeout(Duration::from_secs(30))
            .expect("opening a FIFO swapped in after the check blocked");
        assert!(result.unwrap_err().contains("not a regular file"));

        let real = dir.path().join("real.bin");
        std::fs::write(&real, [1u8; 8]).unwrap();
        let link = dir.path().join("link.bin");
        std::os::unix::fs::symlink(&real, &link).unwrap();
        assert_eq!(read_bounded(&real, 8).unwrap(), [1u8; 8]);
        assert!(read_bounded(&link, 8).is_err());
    }
}
