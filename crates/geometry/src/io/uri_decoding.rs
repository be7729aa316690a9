//! The two decodings a glTF buffer URI needs: percent-decoding of a relative reference
//! (RFC 3986 §2.1) and base64 of a `data:` URI payload (RFC 4648 §4, RFC 2397).
//!
//! Both are a few lines, written here so the glTF reader needs none of the `gltf` crate's
//! `import` feature (which follows any path and pulls in an image decoder).

/// Decodes `%XX` escapes (either hex case); every other byte is kept. `None` when a `%` is
/// not followed by two hex digits.
pub(crate) fn percent_decode(text: &str) -> Option<Vec<u8>> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut at = 0;
    while let Some(&byte) = bytes.get(at) {
        if byte == b'%' {
            let high = hex_digit(*bytes.get(at + 1)?)?;
            let low = hex_digit(*bytes.get(at + 2)?)?;
            out.push((high << 4) | low);
            at += 3;
        } else {
            out.push(byte);
            at += 1;
        }
    }
    Some(out)
}

fn hex_digit(byte: u8) -> Option<u8> {
    char::from(byte)
        .to_digit(16)
        .and_then(|d| u8::try_from(d).ok())
}

/// An upper bound on the bytes [`base64_decode`] returns for `encoded_len` characters,
/// known before decoding (so a size limit can be checked without allocating).
pub(crate) fn base64_decoded_bound(encoded_len: usize) -> usize {
    encoded_len / 4 * 3 + 2
}

/// Decodes standard base64 (`A–Z a–z 0–9 + /`), with or without `=` padding. `None` on any
/// other character (whitespace included), on padding before the end, or on a dangling
/// single character.
pub(crate) fn base64_decode(text: &str) -> Option<Vec<u8>> {
    let body = text.trim_end_matches('=');
    if text.len() - body.len() > 2 || body.len() % 4 == 1 {
        return None;
    }
    let mut out = Vec::with_capacity(base64_decoded_bound(body.len()));
    let (mut bits, mut count) = (0u32, 0u32);
    for byte in body.bytes() {
        let value = match byte {
            b'A'..=b'Z' => byte - b'A',
            b'a'..=b'z' => byte - b'a' + 26,
            b'0'..=b'9' => byte - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        };
        bits = ((bits << 6) | u32::from(value)) & 0xFF_FFFF;
        count += 6;
        if count >= 8 {
            count -= 8;
            out.push((bits >> count) as u8);
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_rfc4648_test_vectors() {
        // RFC 4648 §10.
        for (encoded, decoded) in [
            ("", ""),
            ("Zg==", "f"),
            ("Zm8=", "fo"),
            ("Zm9v", "foo"),
            ("Zm9vYg==", "foob"),
            ("Zm9vYmE=", "fooba"),
            ("Zm9vYmFy", "foobar"),
        ] {
            assert_eq!(
                base64_decode(encoded).as_deref(),
                Some(decoded.as_bytes()),
                "{encoded}"
            );
            // Unpadded input decodes the same.
            let unpadded = encoded.trim_end_matches('=');
            assert_eq!(base64_decode(unpadded).as_deref(), Some(decoded.as_bytes()));
            assert!(base64_decoded_bound(encoded.len()) >= decoded.len());
        }
        // All 64 symbols: 0x00 0x10 0x83 ... is the alphabet in order.
        let all = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let decoded = base64_decode(all).unwrap_or_default();
        assert_eq!(decoded.len(), 48);
        assert_eq!(&decoded[..3], &[0x00, 0x10, 0x83]);
        assert_eq!(&decoded[45..], &[0xF3, 0xDF, 0xBF]);
    }

    #[test]
    fn base64_rejects_bad_characters_padding_and_lengths() {
        for bad in [
            "Zm9v Yg==",
            "Zm9v\nYg==",
            "Zm9vY===",
            "Z",
            "Zm=v",
            "Zm9-",
            "Zm9_",
        ] {
            assert_eq!(base64_decode(bad), None, "{bad:?}");
        }
    }

    #[test]
    fn percent_decoding_of_escapes_and_errors() {
        assert_eq!(
            percent_decode("my%20mesh%2e%62in").as_deref(),
            Some(&b"my mesh.bin"[..])
        );
        assert_eq!(percent_decode("%2F%2f..").as_deref(), Some(&b"//.."[..]));
        assert_eq!(percent_decode("%C3%A9").as_deref(), Some("é".as_bytes()));
        for bad in ["%", "%2", "%G0", "a%2"] {
            assert_eq!(percent_decode(bad), None, "{bad}");
        }
    }
}
