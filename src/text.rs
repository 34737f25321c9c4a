//! Text shown to a user that may carry bytes from a file, a link or an argument: control
//! characters are escaped (`\x1B`, `\n`), so a message can neither clear a terminal nor break a
//! one-line report.

/// `s` with every control character escaped.
pub fn printable(s: &str) -> String {
    if !s.chars().any(char::is_control) {
        return s.to_string();
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        if c.is_control() {
            match c {
                '\n' => out.push_str("\\n"),
                '\r' => out.push_str("\\r"),
                '\t' => out.push_str("\\t"),
                c if (c as u32) < 0x100 => out.push_str(&format!("\\x{:02X}", c as u32)),
                c => out.push_str(&format!("\\u{{{:X}}}", c as u32)),
            }
        } else {
            out.push(c);
        }
    }
    out
}

/// [`printable`], cut to at most `max` characters (with an ellipsis).
pub fn clip(s: &str, max: usize) -> String {
    let p = printable(s);
    if p.chars().count() <= max {
        return p;
    }
    let mut out: String = p.chars().take(max).collect();
    out.push('…');
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_characters_are_escaped() {
        assert_eq!(printable("a\u{1b}[2Jb\n"), "a\\x1B[2Jb\\n");
        assert_eq!(printable("plain é"), "plain é");
        assert_eq!(printable("\u{9b}"), "\\x9B");
        assert_eq!(clip("abcdef", 3), "abc…");
    }
}
