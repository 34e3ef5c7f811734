//! Text layouts besides comma-separated values with a header: columns separated by runs of spaces or tabs
//! (the first line that is not metadata has no comma), turned into commas before parsing, and files without a
//! header row (that line is all numbers), whose columns the reader names by position.

/// The text of a comment line before the header (`#`, or `%` as MATLAB writes them), kept as metadata.
pub(super) fn comment(line: &[u8]) -> Option<&[u8]> {
    line.strip_prefix(b"#").or_else(|| line.strip_prefix(b"%"))
}

/// Whether the first line that is neither metadata nor blank separates its fields by spaces or tabs:
/// it holds no comma and at least two whitespace-separated fields.
pub(super) fn whitespace_separated(bytes: &[u8]) -> bool {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    bytes
        .split(|&b| b == b'\n')
        .find(|l| comment(l).is_none() && !l.iter().all(u8::is_ascii_whitespace))
        .is_some_and(|l| {
            !l.contains(&b',')
                && l.split(u8::is_ascii_whitespace)
                    .filter(|f| !f.is_empty())
                    .nth(1)
                    .is_some()
        })
}

/// The text with every run of spaces and tabs between fields turned into one comma (leading and
/// trailing ones dropped); metadata lines are kept as they are and every line break stays, so line
/// numbers in messages are the file's.
pub(super) fn whitespace_to_commas(bytes: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(bytes.len());
    for (k, line) in bytes.split(|&b| b == b'\n').enumerate() {
        if k > 0 {
            out.push(b'\n');
        }
        if comment(line).is_some() {
            out.extend_from_slice(line);
            continue;
        }
        let fields = line
            .split(u8::is_ascii_whitespace)
            .filter(|f| !f.is_empty());
        for (j, field) in fields.enumerate() {
            if j > 0 {
                out.push(b',');
            }
            out.extend_from_slice(field);
        }
    }
    out
}

/// Whether every comma-separated field of `line` is a number: a data row where a header was expected.
pub(super) fn is_numbers_row(line: &[u8]) -> bool {
    line.split(|&b| b == b',')
        .all(|f| std::str::from_utf8(f).is_ok_and(|f| f.trim().parse::<f64>().is_ok()))
}

/// Whether `line` is a row of units under a header of `columns` names: as many fields, none of them a number
/// and at least one not empty (`s,deg,m/s`, `[s] [rad]`).
pub(super) fn is_units_row(line: &[u8], columns: usize) -> bool {
    let fields: Vec<&str> = match std::str::from_utf8(line) {
        Ok(l) => l.split(',').map(str::trim).collect(),
        Err(_) => return false,
    };
    fields.len() == columns
        && fields.iter().all(|f| f.parse::<f64>().is_err())
        && fields.iter().any(|f| !f.is_empty())
}

#[cfg(test)]
mod tests {
    use std::fs::{self, File};
    use std::path::Path;

    use super::super::*;

    #[test]
    fn text_separated_by_spaces_and_without_a_header_reads_as_its_csv() {
        let csv = "# meta\ntime_s,q_rad_s\n0,0.5\n0.1,-2.5e-1\n0.2,1\n";
        let spaced = "# meta\r\n  time_s \t q_rad_s\r\n 0   0.5\r\n\t0.1\t-2.5e-1  \r\n0.2 1\r\n";
        let expected = parse_csv_bytes(csv.as_bytes(), "f").unwrap();
        let got = parse_csv_bytes(spaced.as_bytes(), "f").unwrap();
        assert_eq!(
            (got.time_s, got.columns),
            (expected.time_s.clone(), expected.columns.clone())
        );

        let map = ColumnMap::parse(
            "[columns]\n1 = { to = \"time_s\" }\n2 = { to = \"q_rad_s\" }\n",
            Path::new("m.toml"),
        )
        .unwrap();
        let headerless = "# meta\n0 0.5\n0.1   -2.5e-1\n0.2\t1\n";
        let got = parse_csv_bytes_mapped(headerless.as_bytes(), "f", Some(&map)).unwrap();
        assert_eq!(
            (&got.time_s, &got.columns),
            (&expected.time_s, &expected.columns)
        );
        // A bad cell is named by the file's own line number; the block-wise path agrees.
        let bad = headerless.replace("0.1 ", "0.1x ");
        let e = parse_csv_bytes_mapped(bad.as_bytes(), "f", Some(&map)).unwrap_err();
        assert!(e.to_string().starts_with("f:3:"), "{e}");
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f.asc");
        fs::write(&path, &bad).unwrap();
        let blocks = read_csv_in_blocks(File::open(&path).unwrap(), "f", 7, Some(&map));
        assert!(matches!(blocks, Err(BlockReadError::Data(b)) if b.to_string() == e.to_string()));
        let e = parse_csv_bytes(headerless.as_bytes(), "f").unwrap_err();
        assert!(
            matches!(
                e,
                DataError::NoHeader {
                    line: 2,
                    columns: 2,
                    ..
                }
            ),
            "{e}"
        );
        // MATLAB's `%` comments before the header and a row of units under it, as data systems export them;
        // the block-wise path agrees (its first block must hold the line after the header).
        let with_units =
            "% ATTAS record\n% 25 Hz\ntime_s  q_rad_s\n[s]  [rad/s]\n0 0.5\n0.1 -2.5e-1\n0.2 1\n";
        let got = parse_csv_bytes(with_units.as_bytes(), "f").unwrap();
        assert_eq!(
            (&got.time_s, &got.columns),
            (&expected.time_s, &expected.columns)
        );
        assert_eq!(
            got.metadata,
            [" ATTAS record", " 25 Hz", " units: [s],[rad/s]"]
        );
        fs::write(dir.path().join("u.asc"), with_units).unwrap();
        for block in [7, 40, 4096] {
            let blocks = read_csv_in_blocks(
                File::open(dir.path().join("u.asc")).unwrap(),
                "f",
                block,
                None,
            );
            assert!(
                matches!(blocks, Ok(ref b) if b.columns == expected.columns),
                "block {block}"
            );
        }
        // A header followed by a row with a number in it is data as before (here a bad one).
        let e = parse_csv_bytes(b"time_s,q_rad_s\ns,1\n0,1\n", "f").unwrap_err();
        assert!(e.to_string().starts_with("f:2:"), "{e}");
        // A weighted sum of columns (an aileron as ½(right − left), in degrees).
        let sums = ColumnMap::parse(
            "[columns]\n1 = { to = \"time_s\" }\n[derived]\n\
             aileron_rad = { from = { 2 = 0.5, 3 = -0.5 }, unit = \"deg\" }\n",
            Path::new("m.toml"),
        )
        .unwrap();
        let got = parse_csv_bytes_mapped(b"0 4 -2\n0.1 1 1\n", "f", Some(&sums)).unwrap();
        let aileron = got.column("aileron_rad").unwrap();
        assert!((aileron[0] - 3f64.to_radians()).abs() < 1e-15 && aileron[1] == 0.0);
        assert_eq!(
            got.column("2"),
            Some(&[4.0, 1.0][..]),
            "the summed columns stay"
        );
        // A comma-separated headerless file is named by position too.
        let commas = headerless.replace("   ", ",").replace([' ', '\t'], ",");
        let got = parse_csv_bytes_mapped(commas.as_bytes(), "f", Some(&map)).unwrap();
        assert_eq!(got.time_s, vec![0.0, 0.1, 0.2]);
    }
}
