//! Allocation-free scanning of ASCII formats (OBJ, PLY ascii, OFF, XYZ): lines, fields,
//! numbers, and splitting a text block into line-aligned chunks for parallel parsing.
//!
//! Floats are parsed with `fast-float2` (the Eisel-Lemire algorithm, correctly rounded like
//! `str::parse` but several times faster and working on bytes, so no UTF-8 check and no
//! per-line `String`); integers with a hand-written loop that checks overflow.

/// Iterates over `(line_number, line)` of `bytes` (1-based numbers), without the `\n` or
/// `\r\n` terminator.
pub(crate) fn lines(bytes: &[u8]) -> impl Iterator<Item = (usize, &[u8])> {
    let mut rest = bytes;
    let mut number = 0usize;
    std::iter::from_fn(move || {
        if rest.is_empty() {
            return None;
        }
        number += 1;
        let (line, next) = match memchr::memchr(b'\n', rest) {
            Some(end) => (&rest[..end], &rest[end + 1..]),
            None => (rest, &rest[rest.len()..]),
        };
        rest = next;
        Some((number, line.strip_suffix(b"\r").unwrap_or(line)))
    })
}

/// The whitespace-separated fields of one line.
pub(crate) fn fields(line: &[u8]) -> impl Iterator<Item = &[u8]> {
    line.split(|b| matches!(b, b' ' | b'\t' | b'\r' | b'\x0b' | b'\x0c'))
        .filter(|f| !f.is_empty())
}

/// Whether a line holds nothing but whitespace.
pub(crate) fn is_blank(line: &[u8]) -> bool {
    line.iter().all(u8::is_ascii_whitespace)
}

/// Parses a whole field as `f32`, or `None`.
pub(crate) fn parse_f32(field: &[u8]) -> Option<f32> {
    fast_float2::parse(field).ok()
}

/// Parses a whole field as `f64`, or `None`.
pub(crate) fn parse_f64(field: &[u8]) -> Option<f64> {
    fast_float2::parse(field).ok()
}

/// Parses a whole field as a signed decimal integer, or `None` (also on overflow).
pub(crate) fn parse_i64(field: &[u8]) -> Option<i64> {
    let (negative, digits) = match field.split_first() {
        Some((b'-', rest)) => (true, rest),
        Some((b'+', rest)) => (false, rest),
        _ => (false, field),
    };
    if digits.is_empty() {
        return None;
    }
    let mut value: i64 = 0;
    for &b in digits {
        if !b.is_ascii_digit() {
            return None;
        }
        value = value.checked_mul(10)?.checked_add(i64::from(b - b'0'))?;
    }
    Some(if negative { -value } else { value })
}

/// Finds where `rows` non-blank lines starting at `bytes[0]` end: returns the byte offset
/// just past the last of them, or `Err(found)` when the text holds fewer.
pub(crate) fn end_of_rows(bytes: &[u8], rows: u64) -> Result<usize, u64> {
    let mut found = 0u64;
    let mut start = 0usize;
    while found < rows {
        if start >= bytes.len() {
            return Err(found);
        }
        let end = memchr::memchr(b'\n', &bytes[start..]).map_or(bytes.len(), |e| start + e + 1);
        if !is_blank(&bytes[start..end]) {
            found += 1;
        }
        start = end;
    }
    Ok(start)
}

/// Splits `bytes` into about `parts` pieces that each end at a line end, for rayon.
pub(crate) fn line_chunks(bytes: &[u8], parts: usize) -> Vec<&[u8]> {
    let target = (bytes.len() / parts.max(1)).max(1 << 16);
    let mut chunks = Vec::with_capacity(parts + 1);
    let mut rest = bytes;
    while rest.len() > target {
        let cut = memchr::memchr(b'\n', &rest[target..]).map_or(rest.len(), |e| target + e + 1);
        let (chunk, next) = rest.split_at(cut);
        chunks.push(chunk);
        rest = next;
    }
    if !rest.is_empty() {
        chunks.push(rest);
    }
    chunks
}

/// Parses the rows of a text block in parallel, one row per non-blank line, in order.
///
/// `parse_row(line, out)` appends what one row yields (zero or more items) or returns a
/// message. On failure returns `(row, message)` with the row's 0-based index in `block`.
pub(crate) fn parse_rows<T, F>(block: &[u8], parse_row: F) -> Result<Vec<T>, (u64, String)>
where
    T: Send,
    F: Fn(&[u8], &mut Vec<T>) -> Result<(), String> + Sync,
{
    use rayon::prelude::*;
    /// Per chunk: rows seen, and its items or the failing row and message.
    type Parsed<T> = (u64, Result<Vec<T>, (u64, String)>);
    let chunks = line_chunks(block, rayon::current_num_threads() * 4);
    let parsed: Vec<Parsed<T>> = chunks
        .par_iter()
        .map(|chunk| {
            let mut out = Vec::new();
            let mut row = 0u64;
            for (_, line) in lines(chunk) {
                if is_blank(line) {
                    continue;
                }
                if let Err(message) = parse_row(line, &mut out) {
                    return (row, Err((row, message)));
                }
                row += 1;
            }
            (row, Ok(out))
        })
        .collect();
    let total = parsed
        .iter()
        .map(|(_, r)| r.as_ref().map_or(0, Vec::len))
        .sum();
    let mut all = Vec::with_capacity(total);
    let mut offset = 0u64;
    for (rows, result) in parsed {
        match result {
            Ok(items) => all.extend(items),
            Err((row, message)) => return Err((offset + row, message)),
        }
        offset += rows;
    }
    Ok(all)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_strip_both_terminators() {
        let got: Vec<_> = lines(b"a\r\nb\n\nc").collect();
        assert_eq!(
            got,
            vec![
                (1, &b"a"[..]),
                (2, &b"b"[..]),
                (3, &b""[..]),
                (4, &b"c"[..])
            ]
        );
    }

    #[test]
    fn numbers_parse_whole_fields_only() {
        assert_eq!(parse_f32(b"-1.5e2"), Some(-150.0));
        assert_eq!(parse_f32(b"1.5x"), None);
        assert_eq!(parse_i64(b"-42"), Some(-42));
        assert_eq!(parse_i64(b"4.0"), None);
        assert_eq!(parse_i64(b"99999999999999999999"), None);
        assert_eq!(parse_i64(b"-"), None);
    }

    #[test]
    fn rows_counted_past_blank_lines() {
        assert_eq!(end_of_rows(b"1\n\n2\n3\n", 2), Ok(5));
        assert_eq!(end_of_rows(b"1\n", 2), Err(1));
        assert_eq!(end_of_rows(b"1", 1), Ok(1));
    }

    #[test]
    fn parallel_rows_keep_order_and_report_the_global_row() {
        let text: String = (0..100_000).map(|i| format!("{i}\n")).collect();
        let parsed = parse_rows(text.as_bytes(), |line, out: &mut Vec<i64>| {
            out.push(parse_i64(line).ok_or("bad")?);
            Ok(())
        })
        .unwrap();
        assert_eq!(parsed, (0..100_000).collect::<Vec<_>>());
        let bad = text.replace("\n77777\n", "\nx\n");
        let err = parse_rows(bad.as_bytes(), |line, out: &mut Vec<i64>| {
            out.push(parse_i64(line).ok_or("bad")?);
            Ok(())
        })
        .unwrap_err();
        assert_eq!(err.0, 77777);
    }
}
