//! Byte-level scanning shared by the text formats (PLY headers, ASCII PLY, OBJ): numbered
//! lines, whitespace-separated tokens, and number parsing.
//!
//! Everything works on `&[u8]` borrowed from the input: no line or token is copied, and a
//! stray non-UTF-8 byte in an OBJ comment costs nothing (only tokens that must be numbers
//! are required to be ASCII).

/// Lines of a byte buffer with their 1-based numbers. A line ends at `\n`, `\r\n` or a lone
/// `\r` (old Mac files; a `\r\r\n` written by a doubled text-mode conversion counts as two
/// lines, as editors show it). The ending is removed. Splitting on `\n` alone would leave a
/// `\r`-only file as one line whose values the tokenizer (which treats `\r` as whitespace)
/// runs together, so a reader would silently take the first record and ignore the rest.
pub(crate) struct Lines<'a> {
    bytes: &'a [u8],
    pos: usize,
    number: u64,
    /// Length of the last line's ending (0 at the end of the input, 1 or 2).
    ending: usize,
}

impl<'a> Lines<'a> {
    /// Lines of `bytes`, the first numbered 1.
    pub(crate) fn new(bytes: &'a [u8]) -> Self {
        Self::starting_at(bytes, 0, 1)
    }

    /// Lines of `bytes` from byte offset `pos`, the first numbered `number`.
    pub(crate) fn starting_at(bytes: &'a [u8], pos: usize, number: u64) -> Self {
        Lines {
            bytes,
            pos: pos.min(bytes.len()),
            number,
            ending: 0,
        }
    }

    /// Byte offset just after the last line returned (its ending included).
    pub(crate) fn offset(&self) -> usize {
        self.pos
    }

    /// The number the next line will get.
    pub(crate) fn next_number(&self) -> u64 {
        self.number
    }

    /// The ending of the last line returned: `b"\n"`, `b"\r\n"`, `b"\r"`, or empty if the
    /// input ended without one.
    pub(crate) fn last_ending(&self) -> &'a [u8] {
        &self.bytes[self.pos - self.ending..self.pos]
    }
}

impl<'a> Iterator for Lines<'a> {
    type Item = (u64, &'a [u8]);

    #[inline]
    fn next(&mut self) -> Option<(u64, &'a [u8])> {
        let rest = self.bytes.get(self.pos..).filter(|r| !r.is_empty())?;
        let (line, ending) = match rest.iter().position(|&b| b == b'\n' || b == b'\r') {
            Some(end) if rest[end] == b'\r' && rest.get(end + 1) == Some(&b'\n') => {
                (&rest[..end], 2)
            }
            Some(end) => (&rest[..end], 1),
            None => (rest, 0),
        };
        self.ending = ending;
        self.pos += line.len() + ending;
        let number = self.number;
        self.number += 1;
        Some((number, line))
    }
}

/// Whitespace-separated tokens of one line.
#[derive(Clone)]
pub(crate) struct Tokens<'a> {
    rest: &'a [u8],
}

impl<'a> Tokens<'a> {
    /// Tokens of `line`.
    pub(crate) fn new(line: &'a [u8]) -> Self {
        Tokens { rest: line }
    }

    /// The rest of the line after the tokens taken so far, without leading whitespace.
    pub(crate) fn remainder(&self) -> &'a [u8] {
        let start = self
            .rest
            .iter()
            .position(|b| !b.is_ascii_whitespace())
            .unwrap_or(self.rest.len());
        &self.rest[start..]
    }
}

impl<'a> Iterator for Tokens<'a> {
    type Item = &'a [u8];

    #[inline]
    fn next(&mut self) -> Option<&'a [u8]> {
        let start = self.rest.iter().position(|b| !b.is_ascii_whitespace())?;
        let rest = &self.rest[start..];
        let end = rest
            .iter()
            .position(|b| b.is_ascii_whitespace())
            .unwrap_or(rest.len());
        self.rest = &rest[end..];
        Some(&rest[..end])
    }
}

/// `bytes` without a leading UTF-8 byte-order mark. Windows editors write one; left in place
/// it sticks to the first keyword (`\u{feff}v`, `\u{feff}ply`), which then goes unrecognised:
/// an OBJ loses its first vertex (and fails later on an index out of range), a PLY its magic.
pub(crate) fn strip_bom(bytes: &[u8]) -> &[u8] {
    bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes)
}

/// True if the line holds only whitespace.
#[inline]
pub(crate) fn is_blank(line: &[u8]) -> bool {
    line.iter().all(u8::is_ascii_whitespace)
}

/// Parses a decimal integer `[+-]?[0-9]+` that fits in `i64`.
#[inline]
pub(crate) fn parse_int(tok: &[u8]) -> Option<i64> {
    let (negative, digits) = match tok {
        [b'-', rest @ ..] => (true, rest),
        [b'+', rest @ ..] => (false, rest),
        _ => (false, tok),
    };
    if digits.is_empty() {
        return None;
    }
    // Accumulate negatively so that i64::MIN parses too.
    let mut value: i64 = 0;
    for &b in digits {
        let d = b.wrapping_sub(b'0');
        if d > 9 {
            return None;
        }
        value = value.checked_mul(10)?.checked_sub(i64::from(d))?;
    }
    if negative {
        Some(value)
    } else {
        value.checked_neg()
    }
}

/// Parses a floating-point number as Rust does (`1`, `-2.5e-3`, `inf`, `NaN`, …); callers
/// reject non-finite results themselves so that the error says "not finite", not "bad".
#[inline]
pub(crate) fn parse_float(tok: &[u8]) -> Option<f64> {
    std::str::from_utf8(tok).ok()?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_strip_endings_and_count() {
        let text = b"ply\r\nformat ascii 1.0\n\nlast";
        let mut lines = Lines::new(text);
        assert_eq!(lines.next(), Some((1, &b"ply"[..])));
        assert_eq!(lines.offset(), 5);
        assert_eq!(lines.next(), Some((2, &b"format ascii 1.0"[..])));
        assert_eq!(lines.next(), Some((3, &b""[..])));
        assert_eq!(lines.next(), Some((4, &b"last"[..])));
        assert_eq!(lines.next(), None);
        assert_eq!(lines.offset(), text.len());
    }

    #[test]
    fn a_lone_carriage_return_ends_a_line() {
        let text = b"v 0 0 0\rv 1 0 0\r\n\rf 1 2 3\r\r\nx\n";
        let mut lines = Lines::new(text);
        let mut next = || {
            let line = lines.next();
            (line, lines.last_ending(), lines.offset())
        };
        assert_eq!(next(), (Some((1, &b"v 0 0 0"[..])), &b"\r"[..], 8));
        assert_eq!(next(), (Some((2, &b"v 1 0 0"[..])), &b"\r\n"[..], 17));
        assert_eq!(next(), (Some((3, &b""[..])), &b"\r"[..], 18));
        assert_eq!(next(), (Some((4, &b"f 1 2 3"[..])), &b"\r"[..], 26));
        assert_eq!(next(), (Some((5, &b""[..])), &b"\r\n"[..], 28));
        assert_eq!(next(), (Some((6, &b"x"[..])), &b"\n"[..], 30));
        assert_eq!(next(), (None, &b"\n"[..], 30));
        let mut unterminated = Lines::new(b"a\rb");
        unterminated.next();
        assert_eq!(unterminated.next(), Some((2, &b"b"[..])));
        assert_eq!(unterminated.last_ending(), b"");
    }

    #[test]
    fn tokens_split_on_any_whitespace() {
        let toks: Vec<&[u8]> = Tokens::new(b"  f\t1/2/3  -4 \x0c5 ").collect();
        assert_eq!(toks, vec![&b"f"[..], b"1/2/3", b"-4", b"5"]);
        let mut t = Tokens::new(b"usemtl  label_1_0 x ");
        t.next();
        assert_eq!(t.remainder(), b"label_1_0 x ");
    }

    #[test]
    fn integers_parse_strictly_with_overflow_checks() {
        assert_eq!(parse_int(b"0"), Some(0));
        assert_eq!(parse_int(b"+17"), Some(17));
        assert_eq!(parse_int(b"-9223372036854775808"), Some(i64::MIN));
        assert_eq!(parse_int(b"9223372036854775807"), Some(i64::MAX));
        assert_eq!(parse_int(b"9223372036854775808"), None);
        for bad in [
            &b""[..],
            b"-",
            b"1.0",
            b"1e3",
            b"0x10",
            b"12a",
            "٣".as_bytes(),
        ] {
            assert_eq!(parse_int(bad), None, "{bad:?}");
        }
    }

    #[test]
    fn floats_parse_including_non_finite() {
        assert_eq!(parse_float(b"-2.5e-3"), Some(-2.5e-3));
        assert_eq!(parse_float(b"1"), Some(1.0));
        assert!(parse_float(b"nan").is_some_and(f64::is_nan));
        assert_eq!(parse_float(b"-inf"), Some(f64::NEG_INFINITY));
        assert_eq!(parse_float(b"1e999"), Some(f64::INFINITY));
        assert_eq!(parse_float(b"1,5"), None);
        assert_eq!(parse_float(&[0xff]), None);
    }
}
