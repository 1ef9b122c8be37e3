//! The CSV reader: a header row naming the columns, fields split with double quotes.

use std::borrow::Cow;
use std::io::BufRead;

use super::{Pass, TextAttributes, TextSchema, hand_on};
use crate::attributes::usable_name;
use crate::columns::ReadOptions;
use crate::error::{ReadError, quoted};
use crate::lines::{Lines, parse_finite};
use crate::ply::check_normals;
use crate::{CloudBuilder, PointCloud, ReadOutcome, SLOT_NAMES};

/// Reads comma-separated values with a header row naming the columns.
///
/// The first non-blank line is the header, after `//` if it starts with that (as
/// CloudCompare and the CSV writer write it); fields are separated by commas, or by
/// semicolons or tabs where the header has those and no comma. A first row holding a single
/// non-negative integer is the point count CloudCompare's export can write: not a point, and
/// the rows after it must be as many ([`ReadError::CountMismatch`]).
/// Names are matched case-insensitively after
/// trimming whitespace and surrounding double quotes; `x`, `y`, `z` are required, `nx`, `ny`,
/// `nz` are optional (all three or none) and any other column is an attribute under its
/// header name (case kept; each character other than an ASCII letter, digit, `_`, `-` or `.`
/// replaced by `_`, `_2`, `_3` … appended to a repeated name, `colN` for an empty name in
/// column `N`), typed as in [`read_xyz_with`](super::read_xyz_with). Every row must have
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
    read_csv_with(reader, name, &ReadOptions::default()).map(|r| r.cloud)
}

/// Reads CSV as [`read_csv`] does; with [`ReadOptions::columns`], those names replace the
/// header row's (which is still skipped, and must have as many fields); columns named `_`
/// are skipped. Normals named `nx`, `ny`, `nz` are taken as normals (a header, unlike a
/// headerless file, says what they are). The notes name the columns dropped because they
/// hold something other than numbers.
///
/// # Errors
/// Those of [`read_csv`], and [`ReadError::ColumnsMismatch`] when the named columns do not
/// match the header.
pub fn read_csv_with(
    reader: impl BufRead,
    name: &str,
    options: &ReadOptions,
) -> Result<ReadOutcome, ReadError> {
    read_csv_slots(reader, name, options, &SLOT_NAMES)
}

/// [`read_csv_with`], reading the leading [`SLOT_NAMES`] `slots` as geometry and any other
/// column as an attribute.
pub(crate) fn read_csv_slots(
    reader: impl BufRead,
    name: &str,
    options: &ReadOptions,
    slots: &[&str],
) -> Result<ReadOutcome, ReadError> {
    let (cloud, schema) = csv_pass(reader, name, options, slots, &mut Pass::Whole)?;
    Ok(ReadOutcome {
        cloud,
        notes: schema.notes,
    })
}

/// One pass over a CSV file ([`read_csv_slots`]) as `pass` says: the cloud (empty unless
/// [`Pass::Whole`]) and what was learnt of its columns.
pub(crate) fn csv_pass<E: From<ReadError>>(
    reader: impl BufRead,
    name: &str,
    options: &ReadOptions,
    slots: &[&str],
    pass: &mut Pass<'_, E>,
) -> Result<(PointCloud, TextSchema), E> {
    let mut lines = Lines::new(reader, 0);
    let Some((header_line, header)) = lines.next_line(name)? else {
        return Err(ReadError::Header {
            file: name.to_owned(),
            line: 1,
            message: "empty file; expected a header row naming the columns x, y, z".to_owned(),
        }
        .into());
    };
    let header_error = |message: String| ReadError::Header {
        file: name.to_owned(),
        line: header_line,
        message,
    };
    // CloudCompare writes its header row as a comment, `//X,Y,Z,...`.
    let header = header.trim_start();
    let header = header.strip_prefix("//").unwrap_or(header);
    // A semicolon separates the fields where the header has it and no comma (spreadsheets in
    // locales with a decimal comma; an option of CloudCompare's export), a tab where it has
    // neither (another of CloudCompare's).
    let separator = if header.contains(',') {
        ','
    } else if header.contains(';') {
        ';'
    } else if header.contains('\t') {
        '\t'
    } else {
        ','
    };
    let mut names = CsvFields::new(header, separator)
        .map(|field| field.map(|f| f.trim().to_owned()))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|message| header_error(message.to_owned()))?;
    if let Some(columns) = &options.columns {
        if columns.len() != names.len() {
            return Err(ReadError::ColumnsMismatch {
                file: name.to_owned(),
                line: header_line,
                found: names.len(),
                named: columns.to_string(),
                by: "--columns".to_owned(),
            }
            .into());
        }
        names = columns.names().to_vec();
    }
    let width = names.len();
    // For each column, the slot of SLOT_NAMES it fills, if any.
    let mut targets = vec![None; width];
    // For each column not in a slot, the attribute it fills, if any.
    let mut attribute_of = vec![None; width];
    let mut attributes = TextAttributes::new(pass);
    let mut taken = std::collections::HashSet::new();
    let mut present = [false; 6];
    for (column, column_name) in names.iter().enumerate() {
        let lowercase = crate::slot_alias(&column_name.to_ascii_lowercase()).to_owned();
        let Some(slot) = slots.iter().position(|n| *n == lowercase) else {
            if column_name == "_" && options.columns.is_some() {
                continue;
            }
            // A name the writers can write back, and unique.
            let name = usable_name(column_name, &format!("col{}", column + 1), &mut taken);
            if let Some(target) = attribute_of.get_mut(column) {
                *target = Some(attributes.add(name, column + 1));
            }
            continue;
        };
        if let Some(flag) = present.get_mut(slot) {
            if *flag {
                return Err(
                    header_error(format!("duplicate column {}", quoted(&lowercase))).into(),
                );
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
            }
            .into());
        }
    }
    check_normals(name, header_line, [nx, ny, nz])?;

    let mut cloud = CloudBuilder::new(nx, 0);
    let mut first_row = true;
    let mut last_line = 0;
    // The point-count line, if the file has one, and the rows read.
    let mut stated: Option<(u64, usize)> = None;
    let mut rows: u64 = 0;
    while let Some((line, text)) = lines.next_line(name)? {
        // CloudCompare's export can put the point count on the line after the header.
        if std::mem::replace(&mut first_row, false)
            && width > 1
            && let Ok(n) = text.trim().parse::<u64>()
        {
            stated = Some((n, line));
            continue;
        }
        let mut values = [0.0; 6];
        let mut found = 0;
        for field in CsvFields::new(text, separator) {
            let column = found + 1;
            found += 1;
            let field = field.map_err(|message| ReadError::Ascii {
                file: name.to_owned(),
                line,
                field: format!("column {column}"),
                message: message.to_owned(),
            })?;
            let Some(&Some(slot)) = targets.get(column - 1) else {
                if let Some(&Some(i)) = attribute_of.get(column - 1) {
                    attributes.push(i, name, line, field.trim())?;
                }
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
            }
            .into());
        }
        last_line = line;
        rows += 1;
        match pass {
            Pass::Whole => cloud.push(values),
            Pass::Profile => {}
            Pass::Batches { max, .. } => {
                cloud.push(values);
                if cloud.points.len() as u64 >= *max {
                    hand_on(&mut cloud, None, &mut attributes, pass, name, line)?;
                }
            }
        }
    }
    super::check_count(name, stated, rows)?;
    if let Pass::Batches { handed, .. } = pass
        && (!*handed || !cloud.points.is_empty())
    {
        hand_on(&mut cloud, None, &mut attributes, pass, name, last_line)?;
    }
    let mut notes = Vec::new();
    let mut cloud = cloud.finish();
    let (kept, columns) = attributes.finish(name, |_| false, &mut notes);
    if matches!(pass, Pass::Whole) {
        cloud.attributes = kept;
    }
    let schema = match pass.schema() {
        Some(schema) => schema.clone(),
        None => TextSchema {
            columns,
            normals: false,
            notes,
            csv: true,
        },
    };
    Ok((cloud, schema))
}

/// The fields of one CSV line, unquoted. Yields an error message for a malformed quoted field
/// and then stops.
#[derive(Debug)]
struct CsvFields<'a> {
    rest: Option<&'a str>,
    separator: char,
}

impl<'a> CsvFields<'a> {
    fn new(line: &'a str, separator: char) -> Self {
        Self {
            rest: Some(line),
            separator,
        }
    }
}

impl<'a> Iterator for CsvFields<'a> {
    type Item = Result<Cow<'a, str>, &'static str>;

    fn next(&mut self) -> Option<Self::Item> {
        let text = self.rest.take()?;
        let Some(mut quoted) = text.trim_start().strip_prefix('"') else {
            // The common case: no quotes, so the field borrows from the line.
            return Some(Ok(Cow::Borrowed(match text.split_once(self.separator) {
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
            return match after.strip_prefix(self.separator) {
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
        CsvFields::new(line, ',')
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
