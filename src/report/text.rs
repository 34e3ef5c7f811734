//! Terminal text: paragraphs wrapped and tables fitted to a width, so no line a command prints runs past
//! [`TERMINAL_WIDTH`] columns.

use super::Table;

/// Widest line a command prints on the terminal, characters.
pub const TERMINAL_WIDTH: usize = 120;

/// Wraps `text` at spaces into lines of at most `width` characters (a single longer word stays whole), the first
/// line prefixed by `first`, the others by `rest`.
pub fn wrap(text: &str, width: usize, first: &str, rest: &str) -> Vec<String> {
    let mut lines = Vec::new();
    let mut line = first.to_string();
    let mut empty = true;
    for word in text.split_whitespace() {
        let len = line.chars().count() + usize::from(!empty) + word.chars().count();
        if !empty && len > width {
            lines.push(std::mem::replace(&mut line, rest.to_string()));
            empty = true;
        }
        if !empty {
            line.push(' ');
        }
        line.push_str(word);
        empty = false;
    }
    if !empty {
        lines.push(line);
    }
    lines
}

/// Renders a table as aligned text within `width` columns: the caption wrapped, then the header and the rows.
/// When the natural layout is too wide, the widest column is wrapped inside its cell (continuation lines leave
/// the other cells blank); when even that cannot fit, each row is printed as `header: value` lines.
pub fn text_table(t: &Table, width: usize) -> String {
    let ncol = t.header.len();
    let mut widths = vec![0usize; ncol];
    for row in std::iter::once(&t.header).chain(&t.rows) {
        for (i, c) in row.iter().enumerate().take(ncol) {
            widths[i] = widths[i].max(c.chars().count());
        }
    }
    let mut out = wrap(&t.caption, width, "", "").join("\n");
    out.push('\n');
    let total = widths.iter().sum::<usize>() + 2 * ncol.saturating_sub(1);
    let widest = (0..ncol).max_by_key(|&i| widths[i]).unwrap_or(0);
    let avail =
        width.saturating_sub(total.saturating_sub(widths.get(widest).copied().unwrap_or(0)));
    if total > width && avail < 16 {
        for row in &t.rows {
            for (h, c) in t.header.iter().zip(row) {
                let head = format!("  {h}: ");
                let pad = " ".repeat(head.chars().count().min(24));
                for l in wrap(c, width, &head, &pad) {
                    out.push_str(&l);
                    out.push('\n');
                }
            }
            out.push('\n');
        }
        return out;
    }
    let wrapped = total > width;
    if wrapped {
        widths[widest] = avail;
    }
    let mut emit = |row: &Vec<String>| {
        let cells: Vec<Vec<String>> = row
            .iter()
            .enumerate()
            .take(ncol)
            .map(|(i, c)| {
                if wrapped && i == widest {
                    let lines = wrap(c, widths[i], "", "");
                    if lines.is_empty() {
                        vec![String::new()]
                    } else {
                        lines
                    }
                } else {
                    vec![c.clone()]
                }
            })
            .collect();
        let height = cells.iter().map(Vec::len).max().unwrap_or(1);
        for k in 0..height {
            let line = cells
                .iter()
                .enumerate()
                .map(|(i, lines)| {
                    let c = lines.get(k).map(String::as_str).unwrap_or("");
                    if i == 0 || (wrapped && i == widest) {
                        format!("{c:<w$}", w = widths[i])
                    } else {
                        format!("{c:>w$}", w = widths[i])
                    }
                })
                .collect::<Vec<_>>()
                .join("  ");
            out.push_str(line.trim_end());
            out.push('\n');
        }
    };
    emit(&t.header);
    for r in &t.rows {
        emit(r);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrapped_lines_stay_within_the_width_and_keep_every_word() {
        let text = "equation error fits one-step predictions (99.98 % one step ahead), not the simulated response";
        let lines = wrap(text, 30, "  - ", "    ");
        assert!(lines.iter().all(|l| l.chars().count() <= 30), "{lines:?}");
        let joined: Vec<&str> = lines.iter().flat_map(|l| l.split_whitespace()).collect();
        assert_eq!(joined[1..].join(" "), text);
    }

    #[test]
    fn a_table_with_a_long_note_column_fits_the_width() {
        let note = "word ".repeat(100);
        let t = Table::new(
            "caption",
            &["name", "value", "note"],
            vec![vec!["Cm_q".into(), "-12.3".into(), note.clone()]],
        );
        let text = text_table(&t, 60);
        assert!(text.lines().all(|l| l.chars().count() <= 60), "{text}");
        assert_eq!(text.matches("word").count(), 100);
        let many = Table {
            caption: "many columns".into(),
            header: (0..30).map(|i| format!("column {i}")).collect(),
            rows: vec![(0..30).map(|i| format!("value {i}")).collect()],
        };
        let text = text_table(&many, 60);
        assert!(text.lines().all(|l| l.chars().count() <= 60), "{text}");
    }
}
