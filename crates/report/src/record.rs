//! Who the report is of and by, and the operator's notes: printed at the top of the page, each
//! left as a line to fill in by hand when not given, so a printed report can be completed.

use crate::html::esc;

/// The patient, the operator and the notes the report is headed with.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Record {
    /// The patient's name or file number.
    pub patient: Option<String>,
    /// Who recorded the session.
    pub operator: Option<String>,
    /// Free-form notes; line breaks are kept.
    pub notes: Option<String>,
}

impl Record {
    /// The first field whose text [`RecordField::check`] refuses, and why.
    pub fn check(&self) -> Result<(), (RecordField, String)> {
        let fields = [
            (RecordField::Patient, &self.patient),
            (RecordField::Operator, &self.operator),
            (RecordField::Notes, &self.notes),
        ];
        for (f, v) in fields {
            if let Some(v) = v {
                f.check(v).map_err(|why| (f, why))?;
            }
        }
        Ok(())
    }
}

/// One of a [`Record`]'s fields, with the limits its text is checked against.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RecordField {
    /// [`Record::patient`].
    Patient,
    /// [`Record::operator`].
    Operator,
    /// [`Record::notes`].
    Notes,
}

impl RecordField {
    /// Its name: `patient`, `operator` or `notes` (the `jawtrack report` flags are named alike).
    pub fn name(self) -> &'static str {
        match self {
            RecordField::Patient => "patient",
            RecordField::Operator => "operator",
            RecordField::Notes => "notes",
        }
    }

    /// The most characters it may hold: a name fits a line of the page, the notes a paragraph.
    pub fn max_chars(self) -> usize {
        match self {
            RecordField::Patient | RecordField::Operator => 200,
            RecordField::Notes => 2000,
        }
    }

    /// Why `text` cannot fill this field, if it cannot: longer than [`RecordField::max_chars`], or
    /// holding a control character (the notes may hold line breaks, a name not even those).
    pub fn check(self, text: &str) -> Result<(), String> {
        let n = text.chars().count();
        if n > self.max_chars() {
            return Err(format!("{n} characters; at most {} are accepted", self.max_chars()));
        }
        let allowed = |c: char| self == RecordField::Notes && c == '\n';
        if let Some((k, c)) = text.chars().enumerate().find(|&(_, c)| c.is_control() && !allowed(c)) {
            let rule = if self == RecordField::Notes {
                "the notes may hold line breaks but no other control character"
            } else {
                "it must be one line without control characters"
            };
            return Err(format!("control character U+{:04X} at character {}: {rule}", c as u32, k + 1));
        }
        Ok(())
    }
}

/// A blank to write a name on.
const LINE: &str = "________________________________________";

/// The record's rows for the session's table: each field escaped, or a line to fill in by hand
/// (three for the notes) when it is not given or blank.
pub(crate) fn rows(r: &Record) -> Vec<(&'static str, String)> {
    let given = |v: &Option<String>| v.as_deref().filter(|v| !v.trim().is_empty()).map(esc);
    let blank = |lines: usize| format!("<span class=\"fill\">{}</span>", vec![LINE; lines].join("<br>"));
    vec![
        ("Patient", given(&r.patient).unwrap_or_else(|| blank(1))),
        ("Operator", given(&r.operator).unwrap_or_else(|| blank(1))),
        ("Notes", given(&r.notes).map_or_else(|| blank(3), |n| n.replace('\n', "<br>"))),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_count_characters_not_bytes() {
        assert!(RecordField::Patient.check(&"é".repeat(200)).is_ok());
        assert_eq!(
            RecordField::Patient.check(&"é".repeat(201)),
            Err("201 characters; at most 200 are accepted".into())
        );
        assert!(RecordField::Notes.check(&"x".repeat(2000)).is_ok());
        assert!(RecordField::Notes.check(&"x".repeat(2001)).is_err());
    }

    #[test]
    fn only_the_notes_keep_line_breaks() {
        assert!(RecordField::Notes.check("left TMJ clicks\nopening limited").is_ok());
        let e = RecordField::Operator.check("Dr A\nB").expect_err("a line break in a name");
        assert!(e.starts_with("control character U+000A at character 5"), "{e}");
        let e = RecordField::Notes.check("a\tb").expect_err("a tab");
        assert!(e.contains("U+0009") && e.contains("line breaks but no other"), "{e}");
    }

    #[test]
    fn blank_fields_are_lines_to_fill_in() {
        let r = Record { patient: Some("  ".into()), operator: None, notes: Some("<b>x</b>\ny".into()) };
        let given = rows(&r);
        assert_eq!(given[0].1, format!("<span class=\"fill\">{LINE}</span>"), "blank is not given");
        assert_eq!(given[2].1, "&lt;b&gt;x&lt;/b&gt;<br>y");
        assert_eq!(rows(&Record::default())[2].1.matches(LINE).count(), 3, "room for notes");
    }
}
