//! Readers for the plain-text formats: whitespace-separated XYZ/TXT/PTS and CSV with a header.

use std::borrow::Cow;
use std::io::BufRead;

use crate::error::{ReadError, quoted};
use crate::lines::{Lines, parse_finite};
use crate::ply::check_normals;
use crate::{CloudBuilder, PointCloud, SLOT_NAMES};

/// Reads whitespace-separated rows of `x y z` or `x y z nx ny nz`.
///
/// Blank lines and lines whose first non-blank character is `#` are ignored. The first data
/// row fixes the column count, which must be 3 (points) or 6 (points and normals); every later
/// row must have as many. Other counts are rejected rather than guessed at: scanner exports
/// such as `x y z intensity r g b` would otherwise be read with colours as normals. A first
/// data row holding a single non-negative integer is the point-count line some scanners write
/// at the top of `.pts` files, and is skipped in every extension since a one-column row is
/// never valid data. `name` is the display name used in errors.
///
/// # Errors
/// [`ReadError::UnsupportedColumnCount`], [`ReadError::ColumnCount`], [`ReadError::Ascii`]
/// for a value that is not a finite number or for text that is not UTF-8, and
/// [`ReadError::Io`].
pub fn read_xyz(reader: impl BufRead, name: &str) -> Result<PointCloud, ReadError> {
    let mut lines = Lines::new(reader, 0);
    let mut columns = None;
    let mut first_row = true;
    let mut cloud = CloudBuilder::new(false, 0);
    while let Some((line, text)) = lines.next_line(name)? {
        if text.trim_start().starts_with('#') {
            continue;
        }
        let mut fields = [""; 6];
        let mut found = 0;
        for token in text.split_ascii_whitespace() {
            if let Some(field) = fields.get_mut(found) {
                *field = token;
            }
            found += 1;
        }
        let expected = match columns {
            Some(expected) => expected,
            None => {
                let is_count_line = found == 1 && fields[0].parse::<u64>().is_ok();
                if std::mem::replace(&mut first_row, false) && is_count_line {
                    continue;
                }
                if found != 3 && found != 6 {
                    return Err(ReadError::UnsupportedColumnCount {
                        file: name.to_owned(),
                        line,
                        found,
                    });
                }
                columns = Some(found);
                cloud = CloudBuilder::new(found == 6, 0);
                found
            }
        };
        if found != expected {
            return Err(ReadError::ColumnCount {
                file: name.to_owned(),
                line,
                found,
                expected,
            });
        }
        let mut values = [0.0; 6];
        for (column, ((value, field), slot_name)) in values
            .iter_mut()
            .zip(fields)
            .zip(SLOT_NAMES)
            .enumerate()
            .take(found)
        {
            *value = parse_finite(field).map_err(|message| ReadError::Ascii {
                file: name.to_owned(),
                line,
                field: format!("column {} ({slot_name})", column + 1),
                message,
            })?;
        }
        cloud.push(values);
    }
    Ok(cloud.finish())
}

/// Reads comma-separated values with a header row naming the columns.
///
/// The first non-blank line is the header. Names are matched case-insensitively after
/// trimming whitespace and surrounding double quotes; `x`, `y`, `z` are required, `nx`, `ny`,
/// `nz` are optional (all three or none) and any other column is ignored. Every row must have
/// as many fields as the header. Fields may be double-quoted (with `""` for a quote inside),
/// so text columns containing commas are skipped correctly; a quoted field may not span lines.
/// Blank lines are ignored. A header without rows gives an empty cloud. `name` is the display
/// name used in errors.
///
/// # Errors
/// [`ReadError::Header`] for an empty file, a malformed or duplicated header name,
/// [`ReadError::MissingField`], [`ReadError::PartialNormals`], [`ReadError::ColumnCount`],
/// [`ReadError::Ascii`] for a value that is not a finite number, and [`ReadError::Io`].
pub fn read_csv(reader: impl BufRead, name: &str) -> Result<PointCloud, ReadError> {
    let mut lines = Lines::new(reader, 0);
    let Some((header_line, header)) = lines.next_line(name)? else {
        return Err(ReadError::Header {
            file: name.to_owned(),
            line: 1,
            message: "empty file; expected a header row naming the columns x, y, z".to_owned(),
        });
    };
    let header_error = |message: String| ReadError::Header {
        file: name.to_owned(),
        line: header_line,
        message,
    };
    let names = CsvFields::new(header)
        .map(|field| field.map(|f| f.trim().to_ascii_lowercase()))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|message| header_error(message.to_owned()))?;
    let width = names.len();
    // For each column, the slot of SLOT_NAMES it fills, if any.
    let mut targets = vec![None; width];
    let mut present = [false; 6];
    for (column, column_name) in names.iter().enumerate() {
        let Some(slot) = SLOT_NAMES.iter().position(|n| n == column_name) else {
            continue;
        };
        if let Some(flag) = present.get_mut(slot) {
            if *flag {
                return Err(header_error(format!(
                    "duplicate column {}",
                    quoted(column_name)
                )));
            }
            *flag = true;
        }
        if let Some(target) = targets.get_mut(column) {
            *target = Some(slot);
        }
    }
    let [x, y, z, nx, ny, nz] = present;
    for (found, field) in [(x, "x"), (y, "y"), (z, "z")] {
        if !found {
            return Err(ReadError::MissingField {
                file: name.to_owned(),
                line: header_line,
                field,
            });
        }
    }
    check_normals(name, header_line, [nx, ny, nz])?;

    let mut cloud = CloudBuilder::new(nx, 0);
    while let Some((line, text)) = lines.next_line(name)? {
        let mut values = [0.0; 6];
        let mut found = 0;
        for field in CsvFields::new(text) {
            let column = found + 1;
            found += 1;
            let field = field.map_err(|message| ReadError::Ascii {
                file: name.to_owned(),
                line,
                field: format!("column {column}"),
                message: message.to_owned(),
            })?;
            let Some(&Some(slot)) = targets.get(column - 1) else {
                continue;
            };
            let value = parse_finite(field.trim()).map_err(|message| ReadError::Ascii {
                file: name.to_owned(),
                line,
                field: format!(
                    "column {column} ({})",
                    SLOT_NAMES.get(slot).copied().unwrap_or("?")
                ),
                message,
            })?;
            if let Some(dst) = values.get_mut(slot) {
                *dst = value;
            }
        }
        if found != width {
            return Err(ReadError::ColumnCount {
                file: name.to_owned(),
                line,
                found,
                expected: width,
            });
        }
        cloud.push(values);
    }
    Ok(cloud.finish())
}

/// The fields of one CSV line, unquoted. Yields an error message for a malformed quoted field
/// and then stops.
#[derive(Debug)]
struct CsvFields<'a> {
    rest: Option<&'a str>,
}

impl<'a> CsvFields<'a> {
    fn new(line: &'a str) -> Self {
        Self { rest: Some(line) }
    }
}

impl<'a> Iterator for CsvFields<'a> {
    type Item = Result<Cow<'a, str>, &'static str>;

    fn next(&mut self) -> Option<Self::Item> {
        let text = self.rest.take()?;
        let Some(mut quoted) = text.trim_start().strip_prefix('"') else {
            // The common case: no quotes, so the field borrows from the line.
            return Some(Ok(Cow::Borrowed(match text.split_once(',') {
                Some((field, rest)) => {
                    self.rest = Some(rest);
                    field
                }
                None => text,
            })));
        };
        let mut field = String::new();
        loop {
            let Some((chunk, after)) = quoted.split_once('"') else {
                return Some(Err("unterminated quoted field"));
            };
            field.push_str(chunk);
            if let Some(after) = after.strip_prefix('"') {
                // A doubled quote stands for one quote inside the field.
                field.push('"');
                quoted = after;
                continue;
            }
            let after = after.trim_start();
            if after.is_empty() {
                return Some(Ok(Cow::Owned(field)));
            }
            return match after.strip_prefix(',') {
                Some(rest) => {
                    self.rest = Some(rest);
                    Some(Ok(Cow::Owned(field)))
                }
                None => Some(Err("text after a closing quote")),
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fields(line: &str) -> Result<Vec<String>, &'static str> {
        CsvFields::new(line)
            .map(|f| f.map(Cow::into_owned))
            .collect()
    }

    #[test]
    fn splits_plain_and_quoted_fields() {
        assert_eq!(fields("a, b ,c").unwrap(), ["a", " b ", "c"]);
        assert_eq!(fields("").unwrap(), [""]);
        assert_eq!(fields("1,").unwrap(), ["1", ""]);
        assert_eq!(
            fields(r#" "x" ,"a,b","say ""hi""",3"#).unwrap(),
            ["x", "a,b", r#"say "hi""#, "3"]
        );
        assert_eq!(fields(r#""open"#), Err("unterminated quoted field"));
        assert_eq!(fields(r#""a"b,c"#), Err("text after a closing quote"));
    }
}
