//! A small, allocation-bounded base64 decoder for glTF `data:` URIs.
//!
//! Accepts the standard (`+/`) and URL-safe (`-_`) alphabets, optional `=` padding and
//! ASCII whitespace anywhere. Anything else is an error, reported by byte offset.

/// Why a base64 payload could not be decoded.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Base64Error {
    /// A byte outside the alphabet at this offset of the payload.
    InvalidByte { offset: usize, byte: u8 },
    /// Data after `=` padding, or a dangling single character in the last group.
    BadPadding,
}

impl std::fmt::Display for Base64Error {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Base64Error::InvalidByte { offset, byte } => {
                write!(f, "invalid base64 character 0x{byte:02x} at offset {offset}")
            }
            Base64Error::BadPadding => write!(f, "invalid base64 padding"),
        }
    }
}

fn sextet(b: u8) -> Option<u8> {
    match b {
        b'A'..=b'Z' => Some(b - b'A'),
        b'a'..=b'z' => Some(b - b'a' + 26),
        b'0'..=b'9' => Some(b - b'0' + 52),
        b'+' | b'-' => Some(62),
        b'/' | b'_' => Some(63),
        _ => None,
    }
}

/// Decodes base64 `input`. The output is at most `3 * input.len() / 4 + 3` bytes.
pub fn decode(input: &[u8]) -> Result<Vec<u8>, Base64Error> {
    let mut out = Vec::with_capacity(input.len() / 4 * 3 + 3);
    let mut acc: u32 = 0;
    let mut n = 0u32; // sextets in `acc`
    let mut padded = false;
    for (offset, &b) in input.iter().enumerate() {
        if b.is_ascii_whitespace() {
            continue;
        }
        if b == b'=' {
            padded = true;
            continue;
        }
        if padded {
            return Err(Base64Error::BadPadding);
        }
        let s = sextet(b).ok_or(Base64Error::InvalidByte { offset, byte: b })?;
        acc = (acc << 6) | u32::from(s);
        n += 1;
        if n == 4 {
            out.extend_from_slice(&[(acc >> 16) as u8, (acc >> 8) as u8, acc as u8]);
            acc = 0;
            n = 0;
        }
    }
    match n {
        0 => {}
        1 => return Err(Base64Error::BadPadding),
        2 => out.push((acc >> 4) as u8),
        _ => out.extend_from_slice(&[(acc >> 10) as u8, (acc >> 2) as u8]),
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::decode;

    #[test]
    fn round_trips_known_vectors() {
        assert_eq!(decode(b"").unwrap(), b"");
        assert_eq!(decode(b"Zg==").unwrap(), b"f");
        assert_eq!(decode(b"Zm8=").unwrap(), b"fo");
        assert_eq!(decode(b"Zm9v").unwrap(), b"foo");
        assert_eq!(decode(b"Zm9vYmFy").unwrap(), b"foobar");
        assert_eq!(decode(b"Zm9v\nYmE").unwrap(), b"fooba");
        assert_eq!(decode(b"_-8=").unwrap(), [0xff, 0xef]);
        assert!(decode(b"Zm9v!").is_err());
        assert!(decode(b"Zg==Zg").is_err());
        assert!(decode(b"Z").is_err());
    }
}
