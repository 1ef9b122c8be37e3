//! Line-by-line reading shared by the text readers (ASCII PLY body, XYZ, CSV).

use std::io::BufRead;

use crate::error::ReadError;

/// The UTF-8 byte-order mark some spreadsheet programs put at the start of a text file.
const BOM: &[u8] = b"\xEF\xBB\xBF";

/// Reads non-blank lines and counts every line, blank or not, so errors can name the line.
#[derive(Debug)]
pub(crate) struct Lines<R> {
    reader: R,
    buf: Vec<u8>,
    /// The number of the last line read (1-based; 0 before the first).
    line: usize,
}

impl<R: BufRead> Lines<R> {
    /// Starts reading at line `lines_before + 1`, so a body after a header keeps the file's
    /// line numbers.
    pub(crate) fn new(reader: R, lines_before: usize) -> Self {
        Self {
            reader,
            buf: Vec::with_capacity(256),
            line: lines_before,
        }
    }

    /// The number of the last line read.
    pub(crate) fn line(&self) -> usize {
        self.line
    }

    /// Returns the next line that is not blank, with its number and without its line ending,
    /// or `None` at the end of the input.
    pub(crate) fn next_line(&mut self, file: &str) -> Result<Option<(usize, &str)>, ReadError> {
        loop {
            self.buf.clear();
            let read = self
                .reader
                .read_until(b'\n', &mut self.buf)
                .map_err(|error| ReadError::Io {
                    file: file.to_owned(),
                    error,
                })?;
            if read == 0 {
                return Ok(None);
            }
            self.line += 1;
            if !self.buf.iter().all(u8::is_ascii_whitespace) {
                break;
            }
        }
        let mut bytes = strip_line_ending(&self.buf);
        if self.line == 1 {
            bytes = bytes.strip_prefix(BOM).unwrap_or(bytes);
        }
        let text = std::str::from_utf8(bytes).map_err(|err| ReadError::Ascii {
            file: file.to_owned(),
            line: self.line,
            field: format!("byte {} of the line", err.valid_up_to() + 1),
            message: "not valid UTF-8 text".to_owned(),
        })?;
        Ok(Some((self.line, text)))
    }
}

/// Removes a trailing `\n` or `\r\n`, so files written on Windows read the same.
pub(crate) fn strip_line_ending(line: &[u8]) -> &[u8] {
    let line = line.strip_suffix(b"\n").unwrap_or(line);
    line.strip_suffix(b"\r").unwrap_or(line)
}

/// Parses one coordinate or normal component. The error message says whether the text is not
/// a number at all or a NaN/infinity (including an overflow such as `1e400`), which the
/// curvature code cannot use.
pub(crate) fn parse_finite(token: &str) -> Result<f64, String> {
    match token.parse::<f64>() {
        Ok(value) if value.is_finite() => Ok(value),
        Ok(_) => Err(format!("non-finite value {}", crate::error::quoted(token))),
        Err(_) if token.replacen(',', ".", 1).parse::<f64>().is_ok() => Err(format!(
            "not a number: {} (a decimal comma? numbers are read with a decimal point: 1.5, not 1,5)",
            crate::error::quoted(token)
        )),
        Err(_) => Err(format!("not a number: {}", crate::error::quoted(token))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_blank_lines_and_strips_crlf_and_bom() {
        let mut lines = Lines::new(&b"\xEF\xBB\xBFa\r\n\n  \nb"[..], 0);
        assert_eq!(lines.next_line("f").unwrap(), Some((1, "a")));
        assert_eq!(lines.next_line("f").unwrap(), Some((4, "b")));
        assert_eq!(lines.next_line("f").unwrap(), None);
    }

    #[test]
    fn rejects_invalid_utf8_with_line() {
        let mut lines = Lines::new(&b"ok\n\xFF\n"[..], 0);
        lines.next_line("f").unwrap();
        let err = lines.next_line("f").unwrap_err().to_string();
        assert!(err.starts_with("f: line 2"), "{err}");
    }

    #[test]
    fn parse_finite_distinguishes_failures() {
        assert_eq!(parse_finite("-1.5e3"), Ok(-1500.0));
        assert!(parse_finite("nan").unwrap_err().contains("non-finite"));
        assert!(parse_finite("1e400").unwrap_err().contains("non-finite"));
        assert!(parse_finite("abc").unwrap_err().contains("not a number"));
    }
}
