//! A column of a text file (XYZ, CSV) read before its type is known: integers until a value
//! is not one, then floats, or dropped at a value that is not a number; finished into an
//! attribute column of the narrowest type that holds it.

use super::{AttributeData, AttributeType, Scalar};

/// A text column on its way to becoming an attribute: integers while every value is one,
/// floats from the first value that is not, and dropped at the first value that is not a
/// number at all. A column that does not `keep` its values learns only its type (the first
/// pass over a file read in batches).
#[derive(Debug)]
pub(crate) struct TextColumn {
    state: State,
    keep: bool,
    /// Whether every integer so far fits an `i32`.
    narrow: bool,
    /// The line of the first value that is not an integer.
    float_from: Option<usize>,
}

#[derive(Debug)]
enum State {
    Integers(Vec<i64>),
    Floats(Vec<f64>),
    /// Not numbers: the line and the text of the first value that is not.
    Dropped(usize, String),
}

/// What a text column turned out to be: its type (`int32`, `int64` or `float64`) and the line
/// from which its values are read as floats (before it, as integers converted to floats).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct TextColumnType {
    pub(crate) ty: AttributeType,
    pub(crate) float_from: Option<usize>,
}

impl TextColumnType {
    /// Appends the value `token` of line `line` to `data` (of this type) exactly as a whole
    /// read of the column would have read it; false if it is not such a value (the file
    /// changed since its type was learnt).
    pub(crate) fn push(self, data: &mut AttributeData, line: usize, token: &str) -> bool {
        let value = match self.ty {
            AttributeType::I32 => token
                .parse::<i64>()
                .ok()
                .and_then(|v| i32::try_from(v).ok())
                .map(Scalar::I32),
            AttributeType::I64 => token.parse::<i64>().ok().map(Scalar::I64),
            _ if self.float_from.is_some_and(|from| line >= from) => {
                token.parse::<f64>().ok().map(Scalar::F64)
            }
            // Integers beyond 2^53 round here, as `TextColumn::push` rounds them.
            _ => token.parse::<i64>().ok().map(|v| Scalar::F64(v as f64)),
        };
        value.is_some_and(|v| data.push(v))
    }
}

impl TextColumn {
    pub(crate) fn new(keep: bool) -> Self {
        Self {
            state: State::Integers(Vec::new()),
            keep,
            narrow: true,
            float_from: None,
        }
    }

    pub(crate) fn push(&mut self, line: usize, token: &str) {
        match &mut self.state {
            State::Integers(values) => {
                if let Ok(v) = token.parse::<i64>() {
                    self.narrow &= i32::try_from(v).is_ok();
                    if self.keep {
                        values.push(v);
                    }
                } else if let Ok(v) = token.parse::<f64>() {
                    // Integers beyond 2^53 round here; a column with a fraction somewhere is
                    // a float column.
                    let mut floats: Vec<f64> = values.iter().map(|&i| i as f64).collect();
                    if self.keep {
                        floats.push(v);
                    }
                    self.float_from = Some(line);
                    self.state = State::Floats(floats);
                } else {
                    self.state = State::Dropped(line, token.to_owned());
                }
            }
            State::Floats(values) => match token.parse::<f64>() {
                Ok(v) => {
                    if self.keep {
                        values.push(v);
                    }
                }
                Err(_) => self.state = State::Dropped(line, token.to_owned()),
            },
            State::Dropped(..) => {}
        }
    }

    /// The column's type, or where it failed.
    pub(crate) fn column_type(&self) -> Result<TextColumnType, (usize, String)> {
        let ty = match &self.state {
            State::Integers(_) if self.narrow => AttributeType::I32,
            State::Integers(_) => AttributeType::I64,
            State::Floats(_) => AttributeType::F64,
            State::Dropped(line, token) => return Err((*line, token.clone())),
        };
        Ok(TextColumnType {
            ty,
            float_from: self.float_from,
        })
    }

    /// The values as an attribute column: `int32` if every value is an integer in its range,
    /// `int64` if every value is an integer, else `float64`; or where the column failed.
    pub(crate) fn finish(self) -> Result<AttributeData, (usize, String)> {
        match self.state {
            State::Integers(values) if self.narrow => Ok(AttributeData::I32(
                values.iter().map(|&v| v as i32).collect(),
            )),
            State::Integers(values) => Ok(AttributeData::I64(values)),
            State::Floats(values) => Ok(AttributeData::F64(values)),
            State::Dropped(line, token) => Err((line, token)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_columns_keep_integers_integer() {
        let column = |tokens: &[&str]| {
            let mut c = TextColumn::new(true);
            for (i, t) in tokens.iter().enumerate() {
                c.push(i + 1, t);
            }
            c.finish()
        };
        assert_eq!(
            column(&["1", "-2", "255"]),
            Ok(AttributeData::I32(vec![1, -2, 255]))
        );
        assert_eq!(
            column(&["1", "9000000000"]),
            Ok(AttributeData::I64(vec![1, 9_000_000_000]))
        );
        assert_eq!(
            column(&["1", "0.5"]),
            Ok(AttributeData::F64(vec![1.0, 0.5]))
        );
        assert_eq!(column(&["1", "red", "2"]), Err((2, "red".to_owned())));
    }
}
