//! Vertex index lists: the input vertices a tool must treat apart (the landmarks QEM keeps,
//! `meshsimplify simplify --keep`), as text: 0-based indices separated by spaces, commas or
//! line breaks; `#` starts a comment. Whether each index exists is the mesh's business, not
//! the list's.

use super::ascii_scan::{lines, parse_i64};
use super::format_error::{MEMORY, format_error};
use super::read_mesh::read_file;
use crate::error::Result;
use std::path::Path;

/// The vertex indices listed in the text file `path`, in file order (repeats kept).
///
/// Errors: [`crate::Error::Io`] when the file cannot be read, [`crate::Error::Format`]
/// naming the file, the entry and its line when an entry is not an index in `0..2³²`.
///
/// ```
/// # let dir = tempfile::tempdir()?;
/// let path = dir.path().join("landmarks.txt");
/// std::fs::write(&path, "# eyes\n12, 40\n7 3 # nose\n")?;
/// assert_eq!(meshgnn_geometry::read_vertex_list(&path)?, [12, 40, 7, 3]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn read_vertex_list(path: impl AsRef<Path>) -> Result<Vec<u32>> {
    let path = path.as_ref();
    parse_vertex_list(&read_file(path)?, path)
}

/// [`read_vertex_list`] of bytes already in memory; errors name the source `<memory>`.
pub fn read_vertex_list_bytes(bytes: &[u8]) -> Result<Vec<u32>> {
    parse_vertex_list(bytes, Path::new(MEMORY))
}

fn parse_vertex_list(bytes: &[u8], path: &Path) -> Result<Vec<u32>> {
    let mut indices = Vec::new();
    for (number, line) in lines(bytes) {
        let content = line.split(|&b| b == b'#').next().unwrap_or_default();
        let entries = content
            .split(|&b| b == b',' || b.is_ascii_whitespace())
            .filter(|entry| !entry.is_empty());
        for entry in entries {
            let index = parse_i64(entry).and_then(|v| u32::try_from(v).ok());
            indices.push(index.ok_or_else(|| {
                format_error(
                    path,
                    format!("entry {} (line {number})", indices.len()),
                    format!("`{}` is not a vertex index", String::from_utf8_lossy(entry)),
                )
            })?);
        }
    }
    Ok(indices)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn separators_comments_and_bad_entries() {
        assert_eq!(
            read_vertex_list_bytes(b"1,2 ,3\r\n\n 4\t5,,6 # 7 8\n#9\n10").unwrap(),
            [1, 2, 3, 4, 5, 6, 10]
        );
        assert!(read_vertex_list_bytes(b"").unwrap().is_empty());
        for (text, entry) in [
            (&b"1 2\n3 x"[..], "entry 3 (line 2)"),
            (b"-1", "entry 0 (line 1)"),
            (b"4294967296", "entry 0"),
            (b"1.5", "entry 0"),
        ] {
            let message = read_vertex_list_bytes(text).unwrap_err().to_string();
            assert!(
                message.contains(entry) && message.contains("<memory>"),
                "{message}"
            );
            assert!(!message.contains('\n'), "{message}");
        }
        let missing = read_vertex_list("no/such/list.txt")
            .unwrap_err()
            .to_string();
        assert!(missing.contains("no/such/list.txt"), "{missing}");
    }

    proptest::proptest! {
        #[test]
        fn any_list_written_with_any_separators_reads_back(
            indices in proptest::collection::vec(proptest::num::u32::ANY, 0..50),
            separators in proptest::collection::vec(
                proptest::sample::select(vec![" ", ",", ", ", "\n", "\r\n", "\t", " # note\n"]),
                50,
            ),
        ) {
            let mut text = String::new();
            for (index, separator) in indices.iter().zip(&separators) {
                text.push_str(&index.to_string());
                text.push_str(separator);
            }
            proptest::prop_assert_eq!(read_vertex_list_bytes(text.as_bytes()).unwrap(), indices);
        }

        #[test]
        fn any_bytes_give_a_list_or_an_error(bytes in proptest::collection::vec(0u8..=255, 0..200)) {
            let _ = read_vertex_list_bytes(&bytes);
        }
    }
}
