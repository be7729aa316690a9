//! [`GlbBuilder`]: the binary glTF container (GLB) that every glTF writer of this crate fills.
//!
//! glTF 2.0 specification §4.4 "Binary glTF Layout": a 12-byte header (magic `glTF`, version
//! 2, total length), a JSON chunk padded with spaces to a multiple of 4 bytes, and an optional
//! BIN chunk padded with zeros to a multiple of 4; every length is a little-endian `u32`, so a
//! GLB holds at most 4 GiB. The BIN chunk is buffer 0 (§4.4.3.3). Each accessor written here
//! gets a buffer view of its own that starts on a multiple of 4 bytes, which satisfies the
//! alignment rules of §3.6.2.4 for every component type.

/// The `glTF` magic, as a little-endian `u32` it is 0x46546C67.
const MAGIC: &[u8; 4] = b"glTF";
/// Chunk type of the JSON chunk (`JSON` in ASCII).
pub(crate) const JSON_CHUNK: u32 = 0x4E4F_534A;
/// Chunk type of the binary chunk (`BIN\0` in ASCII).
pub(crate) const BIN_CHUNK: u32 = 0x004E_4942;
/// `componentType` of 32-bit floats (§3.6.2.2).
pub(crate) const FLOAT: u32 = 5126;
/// `componentType` of 32-bit unsigned integers.
const UNSIGNED_INT: u32 = 5125;

/// What a buffer view holds, which sets its `target` (§3.6.1.2 and the `bufferView.target`
/// property): vertex attributes (`ARRAY_BUFFER`), vertex indices (`ELEMENT_ARRAY_BUFFER`), or
/// data no GPU buffer binds, such as animation keyframes, which has no target.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ViewTarget {
    /// Vertex attributes and morph-target displacements: 34962.
    Vertices,
    /// Triangle indices: 34963.
    Indices,
    /// Animation inputs and outputs: no `target` member.
    None,
}

/// The binary chunk, buffer views and accessors of a GLB being written; [`GlbBuilder::finish`]
/// adds the rest of the JSON document and lays out the container.
#[derive(Debug, Default)]
pub(crate) struct GlbBuilder {
    bin: Vec<u8>,
    views: Vec<String>,
    accessors: Vec<String>,
}

impl GlbBuilder {
    /// Appends `data` as a new buffer view and one accessor over all of it; `accessor` holds
    /// the accessor's JSON members other than `bufferView`, e.g.
    /// `"componentType":5126,"count":3,"type":"VEC3"`. Returns the accessor's index.
    pub(crate) fn add(
        &mut self,
        data: impl IntoIterator<Item = u8>,
        accessor: &str,
        target: ViewTarget,
    ) -> usize {
        let offset = self.bin.len();
        self.bin.extend(data);
        let length = self.bin.len() - offset;
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let target = match target {
            ViewTarget::Vertices => r#","target":34962"#,
            ViewTarget::Indices => r#","target":34963"#,
            ViewTarget::None => "",
        };
        self.views.push(format!(
            r#"{{"buffer":0,"byteOffset":{offset},"byteLength":{length}{target}}}"#
        ));
        let view = self.views.len() - 1;
        self.accessors
            .push(format!(r#"{{"bufferView":{view},{accessor}}}"#));
        self.accessors.len() - 1
    }

    /// Appends `values: #values×N` as an f32 accessor (`SCALAR`, `VEC2`, `VEC3` or `VEC4`),
    /// with its component-wise `min` and `max` when `bounds` is set: the specification
    /// requires them on `POSITION` accessors, morph targets included (§3.7.2.1), and on
    /// animation sampler inputs (§3.11). The values must be finite.
    pub(crate) fn add_floats<const N: usize>(
        &mut self,
        values: &[[f32; N]],
        bounds: bool,
        target: ViewTarget,
    ) -> usize {
        let kind = match N {
            1 => "SCALAR",
            2 => "VEC2",
            3 => "VEC3",
            _ => "VEC4",
        };
        let count = values.len();
        let mut accessor = format!(r#""componentType":{FLOAT},"count":{count},"type":"{kind}""#);
        if bounds {
            let mut min = [f32::INFINITY; N];
            let mut max = [f32::NEG_INFINITY; N];
            for value in values {
                for (c, &x) in value.iter().enumerate() {
                    min[c] = min[c].min(x);
                    max[c] = max[c].max(x);
                }
            }
            accessor += &format!(
                r#","min":{},"max":{}"#,
                json_floats(&min),
                json_floats(&max)
            );
        }
        let data = values.iter().flatten().flat_map(|x| x.to_le_bytes());
        self.add(data, &accessor, target)
    }

    /// Appends `triangles: #F×3` as a `u32` index accessor.
    pub(crate) fn add_indices(&mut self, triangles: &[[u32; 3]]) -> usize {
        let count = triangles.len() * 3;
        let data = triangles.iter().flatten().flat_map(|i| i.to_le_bytes());
        let accessor = format!(r#""componentType":{UNSIGNED_INT},"count":{count},"type":"SCALAR""#);
        self.add(data, &accessor, ViewTarget::Indices)
    }

    /// The GLB file ([`glb_container`]). `members` are the document's top-level JSON members
    /// besides `asset`, `buffers`, `bufferViews` and `accessors`, each written `"name":value`.
    /// Fails (with the reason) when the file would exceed the 4 GiB a GLB can describe.
    pub(crate) fn finish(self, members: &[String]) -> std::result::Result<Vec<u8>, String> {
        let mut json = String::from(r#"{"asset":{"version":"2.0","generator":"meshgnn-geometry"}"#);
        for member in members {
            json.push(',');
            json += member;
        }
        if !self.bin.is_empty() {
            json += &format!(
                r#","buffers":[{{"byteLength":{}}}],"bufferViews":[{}],"accessors":[{}]"#,
                self.bin.len(),
                self.views.join(","),
                self.accessors.join(",")
            );
        }
        json.push('}');
        glb_container(json.as_bytes(), &self.bin)
    }
}

/// The GLB file holding `json` (padded with spaces) and, when not empty, `bin` (padded with
/// zeros) as buffer 0; fails (with the reason) past the 4 GiB a GLB can describe.
pub(crate) fn glb_container(json: &[u8], bin: &[u8]) -> std::result::Result<Vec<u8>, String> {
    let padded = |n: usize| n.next_multiple_of(4);
    let bin_chunk = if bin.is_empty() {
        0
    } else {
        8 + padded(bin.len())
    };
    let total = 12 + 8 + padded(json.len()) + bin_chunk;
    let length = |n: usize| {
        u32::try_from(n).map_err(|_| {
            format!("{total} bytes is over the 4 GiB (2^32 - 1 bytes) a GLB file can hold")
        })
    };
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&length(total)?.to_le_bytes());
    out.extend_from_slice(&length(padded(json.len()))?.to_le_bytes());
    out.extend_from_slice(&JSON_CHUNK.to_le_bytes());
    out.extend_from_slice(json);
    out.resize(out.len() + padded(json.len()) - json.len(), b' ');
    if !bin.is_empty() {
        out.extend_from_slice(&length(padded(bin.len()))?.to_le_bytes());
        out.extend_from_slice(&BIN_CHUNK.to_le_bytes());
        out.extend_from_slice(bin);
        out.resize(total, 0);
    }
    Ok(out)
}

/// `[a,b,c]` with each float in its shortest form that reads back as the same `f32`.
fn json_floats(values: &[f32]) -> String {
    let parts: Vec<String> = values.iter().map(|x| format!("{x:?}")).collect();
    format!("[{}]", parts.join(","))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn views_start_on_multiples_of_four_and_chunks_are_padded() {
        let mut glb = GlbBuilder::default();
        assert_eq!(glb.add([1u8, 2, 3], r#""x":0"#, ViewTarget::None), 0);
        assert_eq!(
            glb.add_floats(&[[1.5f32], [-2.0]], true, ViewTarget::None),
            1
        );
        assert_eq!(glb.add_indices(&[[0, 1, 2]]), 2);
        assert_eq!(
            glb.views,
            [
                r#"{"buffer":0,"byteOffset":0,"byteLength":3}"#,
                r#"{"buffer":0,"byteOffset":4,"byteLength":8}"#,
                r#"{"buffer":0,"byteOffset":12,"byteLength":12,"target":34963}"#,
            ]
        );
        assert_eq!(
            glb.accessors[1],
            r#"{"bufferView":1,"componentType":5126,"count":2,"type":"SCALAR","min":[-2.0],"max":[1.5]}"#
        );
        let bytes = glb.finish(&[r#""scene":0"#.to_owned()]).unwrap();
        assert_eq!(&bytes[..4], b"glTF");
        assert_eq!(bytes.len() % 4, 0);
        let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
        assert_eq!(word(8), bytes.len());
        let json_length = word(12);
        assert_eq!(json_length % 4, 0);
        let json = std::str::from_utf8(&bytes[20..20 + json_length]).unwrap();
        assert!(json.starts_with(r#"{"asset":{"version":"2.0","generator":"meshgnn-geometry"},"scene":0,"buffers":[{"byteLength":24}]"#), "{json}");
        assert_eq!(word(20 + json_length), 24);
        assert_eq!(word(24 + json_length) as u32, BIN_CHUNK);
    }

    #[test]
    fn the_container_pads_json_with_spaces_and_bin_with_zeros() {
        let glb = glb_container(b"{}", &[7]).unwrap();
        assert_eq!(glb.len(), 12 + 8 + 4 + 8 + 4);
        assert_eq!(&glb[20..24], b"{}  ");
        assert_eq!(&glb[32..], [7, 0, 0, 0]);
        assert_eq!(glb_container(b"{}", &[]).unwrap().len(), 24);
    }
}
