//! The PLY header: format, elements, and their (possibly list) properties.
//!
//! ```text
//! ply
//! format binary_little_endian 1.0      (or ascii / binary_big_endian; any version string)
//! comment …                            (comments and obj_info lines are ignored)
//! element vertex 8
//! property double x                    (any scalar type; float and double are usual)
//! property list uchar int vertex_indices
//! end_header
//! ```
//!
//! Parsing stops at `end_header`; [`Header::data_start`] is the byte just after that line,
//! where binary data begins.

use super::error::shown;
use super::error::{IoErrorKind, Location};
use super::text::{Lines, is_blank};

/// How the data section is encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Encoding {
    /// Whitespace-separated text, one element per line.
    Ascii,
    /// Packed binary, least significant byte first.
    BinaryLittleEndian,
    /// Packed binary, most significant byte first.
    BinaryBigEndian,
}

/// A PLY scalar type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    /// Parses a type name, old (`uchar`) or new (`uint8`) style.
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    /// Size in bytes in binary data.
    pub(crate) fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    /// The name used in messages (the original PLY spelling).
    pub(crate) fn name(self) -> &'static str {
        match self {
            Scalar::I8 => "char",
            Scalar::U8 => "uchar",
            Scalar::I16 => "short",
            Scalar::U16 => "ushort",
            Scalar::I32 => "int",
            Scalar::U32 => "uint",
            Scalar::F32 => "float",
            Scalar::F64 => "double",
        }
    }

    /// The values an integer type holds, `None` for the float types.
    pub(crate) fn int_range(self) -> Option<(i64, i64)> {
        Some(match self {
            Scalar::I8 => (i8::MIN.into(), i8::MAX.into()),
            Scalar::U8 => (0, u8::MAX.into()),
            Scalar::I16 => (i16::MIN.into(), i16::MAX.into()),
            Scalar::U16 => (0, u16::MAX.into()),
            Scalar::I32 => (i32::MIN.into(), i32::MAX.into()),
            Scalar::U32 => (0, u32::MAX.into()),
            Scalar::F32 | Scalar::F64 => return None,
        })
    }

    /// True for the integer types.
    pub(crate) fn is_int(self) -> bool {
        self.int_range().is_some()
    }
}

/// The type of one property.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PropKind {
    /// One value.
    Scalar(Scalar),
    /// A count (always an integer type) followed by that many items.
    List {
        /// Type of the count.
        count: Scalar,
        /// Type of each item.
        item: Scalar,
    },
}

/// One declared property.
#[derive(Clone, Debug)]
pub(crate) struct Property {
    pub(crate) name: String,
    pub(crate) kind: PropKind,
}

/// One declared element: name, count, properties in data order.
#[derive(Clone, Debug)]
pub(crate) struct ElementDecl {
    pub(crate) name: String,
    pub(crate) count: u64,
    pub(crate) props: Vec<Property>,
    /// The header line that declared it (for error messages).
    pub(crate) line: u64,
}

impl ElementDecl {
    /// Index of the property called `name`.
    pub(crate) fn find(&self, name: &str) -> Option<usize> {
        self.props.iter().position(|p| p.name == name)
    }

    /// The fewest bytes one element can take: in binary, its scalars plus the counts of
    /// empty lists; in ASCII, one digit and one separator per property. Used to reject
    /// counts the data cannot hold before allocating anything for them.
    pub(crate) fn min_bytes(&self, encoding: Encoding) -> u64 {
        match encoding {
            Encoding::Ascii => 2 * self.props.len() as u64,
            Encoding::BinaryLittleEndian | Encoding::BinaryBigEndian => self
                .props
                .iter()
                .map(|p| match p.kind {
                    PropKind::Scalar(s) => s.size() as u64,
                    PropKind::List { count, .. } => count.size() as u64,
                })
                .sum(),
        }
    }
}

/// A parsed header.
#[derive(Clone, Debug)]
pub(crate) struct Header {
    pub(crate) encoding: Encoding,
    pub(crate) elements: Vec<ElementDecl>,
    /// Byte offset of the first data byte.
    pub(crate) data_start: usize,
    /// Line number of the first data line (ASCII).
    pub(crate) data_line: u64,
}

/// Most elements, and most properties per element, a header may declare. Real files use a
/// handful; the cap keeps the duplicate-name checks (quadratic) cheap on hostile headers.
pub(crate) const MAX_DECLARATIONS: usize = 1024;

fn bad(line: u64, reason: impl Into<String>) -> IoErrorKind {
    IoErrorKind::BadHeader {
        at: Location::header(line),
        reason: reason.into(),
    }
}

/// Parses the header at the start of `bytes`.
pub(crate) fn parse_header(bytes: &[u8]) -> Result<Header, IoErrorKind> {
    if is_blank(bytes) {
        return Err(IoErrorKind::Empty);
    }
    let mut lines = Lines::new(bytes);
    match lines.next() {
        Some((_, b"ply")) => {}
        _ => return Err(IoErrorKind::BadMagic),
    }
    // A header written with lone `\r` endings ends with `end_header\r`; if binary data then
    // starts with the byte 0x0A, the line splitter would take it for the `\n` of a `\r\n`.
    // The magic line says which ending the writer used.
    let cr_only = lines.last_ending() == b"\r";
    let mut encoding = None;
    let mut elements: Vec<ElementDecl> = Vec::new();
    let mut last_line = 1;
    for (number, raw) in lines.by_ref() {
        last_line = number;
        let line = std::str::from_utf8(raw).map_err(|_| IoErrorKind::NotUtf8 {
            at: Location::header(number),
        })?;
        let mut words = line.split_ascii_whitespace();
        match words.next() {
            None | Some("comment") | Some("obj_info") => {}
            Some("format") => {
                if encoding.is_some() {
                    return Err(bad(number, "second `format` line"));
                }
                encoding = Some(match words.next() {
                    Some("ascii") => Encoding::Ascii,
                    Some("binary_little_endian") => Encoding::BinaryLittleEndian,
                    Some("binary_big_endian") => Encoding::BinaryBigEndian,
                    other => {
                        return Err(bad(
                            number,
                            format!("unknown format {:?}", other.unwrap_or("")),
                        ));
                    }
                });
            }
            Some("element") => {
                let (Some(name), Some(count), None) = (words.next(), words.next(), words.next())
                else {
                    return Err(bad(number, "expected `element <name> <count>`"));
                };
                let count = count.parse::<u64>().map_err(|_| {
                    bad(
                        number,
                        format!("bad element count {:?}", shown(count.as_bytes())),
                    )
                })?;
                if elements.len() >= MAX_DECLARATIONS {
                    return Err(bad(
                        number,
                        format!("more than {MAX_DECLARATIONS} elements"),
                    ));
                }
                if elements.iter().any(|e| e.name == name) {
                    return Err(bad(number, format!("element `{name}` declared twice")));
                }
                elements.push(ElementDecl {
                    name: name.to_owned(),
                    count,
                    props: Vec::new(),
                    line: number,
                });
            }
            Some("property") => {
                let Some(element) = elements.last_mut() else {
                    return Err(bad(number, "`property` before any `element`"));
                };
                let property = parse_property(words, number)?;
                if element.props.len() >= MAX_DECLARATIONS {
                    return Err(bad(
                        number,
                        format!("more than {MAX_DECLARATIONS} properties in one element"),
                    ));
                }
                if element.find(&property.name).is_some() {
                    return Err(bad(
                        number,
                        format!("property `{}` declared twice", property.name),
                    ));
                }
                element.props.push(property);
            }
            Some("end_header") => {
                let encoding =
                    encoding.ok_or_else(|| bad(number, "no `format` line before `end_header`"))?;
                let mut data_start = lines.offset();
                if cr_only && encoding != Encoding::Ascii && lines.last_ending() == b"\r\n" {
                    data_start -= 1;
                }
                return Ok(Header {
                    encoding,
                    elements,
                    data_start,
                    data_line: lines.next_number(),
                });
            }
            Some(other) => {
                return Err(bad(
                    number,
                    format!("unknown header keyword {:?}", shown(other.as_bytes())),
                ));
            }
        }
    }
    Err(IoErrorKind::Truncated {
        at: Location::header(last_line),
    })
}

fn parse_property<'a>(
    mut words: impl Iterator<Item = &'a str>,
    line: u64,
) -> Result<Property, IoErrorKind> {
    let scalar = |word: Option<&str>| {
        let word = word.unwrap_or("");
        Scalar::parse(word).ok_or_else(|| {
            bad(
                line,
                format!("unknown property type {:?}", shown(word.as_bytes())),
            )
        })
    };
    let kind = match words.next() {
        Some("list") => {
            let count = scalar(words.next())?;
            let item = scalar(words.next())?;
            if !count.is_int() {
                return Err(bad(line, "list count type must be an integer type"));
            }
            PropKind::List { count, item }
        }
        word => PropKind::Scalar(scalar(word)?),
    };
    let (Some(name), None) = (words.next(), words.next()) else {
        return Err(bad(line, "expected `property <type> <name>`"));
    };
    Ok(Property {
        name: name.to_owned(),
        kind,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &[u8]) -> IoErrorKind {
        match parse_header(text) {
            Ok(h) => panic!("expected an error, got {h:?}"),
            Err(e) => e,
        }
    }

    #[test]
    fn parses_elements_properties_and_data_offset() {
        let text =
            b"ply\r\nformat binary_big_endian 1.0\ncomment hi\nobj_info x\nelement vertex 2\n\
property float x\nproperty float y\nproperty double z\nelement face 1\n\
property list uchar uint vertex_indices\nproperty int label_front\nend_header\nDATA";
        let h = parse_header(text).unwrap();
        assert_eq!(h.encoding, Encoding::BinaryBigEndian);
        assert_eq!(h.elements.len(), 2);
        assert_eq!(h.elements[0].count, 2);
        assert_eq!(h.elements[0].min_bytes(h.encoding), 16);
        assert_eq!(h.elements[1].find("label_front"), Some(1));
        assert_eq!(
            h.elements[1].props[0].kind,
            PropKind::List {
                count: Scalar::U8,
                item: Scalar::U32
            }
        );
        assert_eq!(&text[h.data_start..], b"DATA");
        assert_eq!(h.data_line, 13);
    }

    #[test]
    fn declaration_counts_are_capped() {
        let mut text = String::from("ply\nformat ascii 1.0\nelement v 1\n");
        for i in 0..MAX_DECLARATIONS {
            text += &format!("property float p{i}\n");
        }
        assert!(parse_header(format!("{text}end_header\n").as_bytes()).is_ok());
        text += "property float one_more\n";
        assert!(
            matches!(err(text.as_bytes()), IoErrorKind::BadHeader { at, .. } if at == Location::header(1028))
        );
        let mut text = String::from("ply\nformat ascii 1.0\n");
        for i in 0..=MAX_DECLARATIONS {
            text += &format!("element e{i} 0\n");
        }
        assert!(matches!(
            err(text.as_bytes()),
            IoErrorKind::BadHeader { .. }
        ));
    }

    #[test]
    fn rejects_malformed_headers_with_their_line() {
        assert!(matches!(err(b""), IoErrorKind::Empty));
        assert!(matches!(err(b" \n"), IoErrorKind::Empty));
        assert!(matches!(err(b"PLY\n"), IoErrorKind::BadMagic));
        assert!(matches!(err(b"solid stl\n"), IoErrorKind::BadMagic));
        assert!(matches!(
            err(b"ply\nformat ascii 1.0\n"),
            IoErrorKind::Truncated { .. }
        ));
        assert!(matches!(
            err(b"ply\nend_header\n"),
            IoErrorKind::BadHeader { .. }
        ));
        assert!(matches!(
            err(b"ply\nformat ascii 1.0\ncomment \xff\xfe\nend_header\n"),
            IoErrorKind::NotUtf8 { at } if at == Location::header(3)
        ));
        for (text, line) in [
            (&b"ply\nformat utf16 1.0\nend_header\n"[..], 2),
            (b"ply\nformat ascii 1.0\nelement vertex -3\nend_header\n", 3),
            (b"ply\nformat ascii 1.0\nproperty float x\nend_header\n", 3),
            (b"ply\nformat ascii 1.0\nelement v 1\nproperty quad x\nend_header\n", 4),
            (b"ply\nformat ascii 1.0\nelement v 1\nproperty list float int x\nend_header\n", 4),
            (b"ply\nformat ascii 1.0\nelement v 1\nproperty float x\nproperty float x\nend_header\n", 5),
            (b"ply\nformat ascii 1.0\nelement v 1\nelement v 2\nend_header\n", 4),
            (b"ply\nformat ascii 1.0\nelement v 1\nproperty float\nend_header\n", 4),
            (b"ply\nformat ascii 1.0\nbogus\nend_header\n", 3),
        ] {
            match err(text) {
                IoErrorKind::BadHeader { at, .. } => assert_eq!(at, Location::header(line), "{text:?}"),
                other => panic!("{text:?}: {other:?}"),
            }
        }
    }
}
