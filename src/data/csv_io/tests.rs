use super::chunk::{eight_digit_value, eight_digits, fast_decimal, long_decimal, scan_cell};
use super::*;
use rand::{Rng, SeedableRng};
use std::fs;

#[test]
fn fast_decimal_path_agrees_bit_for_bit_with_std_parse() {
    // 200k random decimals of 1..19 characters: the fast path must give exactly std's result
    // whenever it answers (Clinger's fast path is exact, so any difference is a bug).
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    let mut answered = 0;
    for _ in 0..200_000 {
        let int_digits = rng.gen_range(0..10);
        let frac_digits = rng.gen_range(0..12);
        let mut s = String::new();
        if rng.gen_bool(0.5) {
            s.push('-');
        }
        for _ in 0..int_digits {
            s.push(char::from(b'0' + rng.gen_range(0..10u8)));
        }
        if frac_digits > 0 || rng.gen_bool(0.3) {
            s.push('.');
        }
        for _ in 0..frac_digits {
            s.push(char::from(b'0' + rng.gen_range(0..10u8)));
        }
        let std = s.parse::<f64>().ok();
        if let Some(v) = fast_decimal(s.as_bytes()) {
            answered += 1;
            assert_eq!(Some(v.to_bits()), std.map(f64::to_bits), "input {s}");
        }
    }
    assert!(answered > 100_000, "fast path used for {answered} inputs");
}

#[test]
fn long_decimal_path_agrees_bit_for_bit_with_std_parse() {
    // 300k shortest round-trip strings of random doubles (16–17 digits) and random 16–19
    // digit decimals: whenever the long path answers it must equal std's correctly rounded
    // result, and it must answer for the vast majority.
    // Hard cases first: near powers of two and exact midpoints between doubles.
    for s in [
        "0.50000000000000001",
        "0.49999999999999997",
        "1.0000000000000001",
        "0.99999999999999994",
        "0.99999999999999989",
        "9007199254740993",
        "9007199254740995",
        "2.2250738585072014",
        "1844674407370955161",
        "0.1000000000000000055511151231257827",
        "7.3786976294838206464",
    ] {
        let (v, _) = scan_cell(s.as_bytes(), 0);
        assert_eq!(
            v.map(f64::to_bits),
            s.parse::<f64>().ok().map(f64::to_bits),
            "{s}"
        );
    }
    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    let (mut answered, mut total) = (0, 0);
    for case in 0..300_000 {
        let s = if case % 2 == 0 {
            let x: f64 = rng.gen_range(-1e3..1e3) * 10f64.powi(rng.gen_range(-6..3));
            format!("{x:?}")
        } else {
            let digits = rng.gen_range(16..=19);
            let mut s = String::new();
            let dot = rng.gen_range(0..digits);
            for d in 0..digits {
                if d == dot {
                    s.push('.');
                }
                s.push(char::from(b'0' + rng.gen_range(0..10u8)));
            }
            s
        };
        if s.contains('e') {
            continue;
        }
        let (v, end) = scan_cell(s.as_bytes(), 0);
        assert_eq!(end, s.len());
        let std = s.parse::<f64>().unwrap();
        assert_eq!(v.map(f64::to_bits), Some(std.to_bits()), "input {s}");
        total += 1;
        let digits: String = s.chars().filter(char::is_ascii_digit).collect();
        let w: u64 = digits.parse().unwrap();
        let k = s.len() - s.find('.').map_or(s.len(), |i| i + 1);
        if w > (1u64 << 53) && k < 23 {
            if let Some(x) = long_decimal(w, k) {
                answered += 1;
                assert_eq!(x.to_bits(), std.abs().to_bits(), "long path, input {s}");
            }
        }
    }
    assert!(
        answered > total / 3,
        "long path answered {answered} of {total}"
    );
}

/// Reads `text` through the block-wise path with tiny blocks, and in memory.
fn both_ways(text: &str) -> (String, String) {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("f.csv");
    fs::write(&path, text).expect("write");
    let blocks = read_csv_in_blocks(File::open(&path).expect("open"), "f.csv", 97, None);
    let blocks = match blocks {
        Ok(r) => format!("{:?} {:?} {:?}", r.time_s, r.columns, r.metadata),
        Err(BlockReadError::Data(e)) => e.to_string(),
        Err(BlockReadError::Io(e)) => panic!("io: {e}"),
    };
    let whole = match parse_csv_bytes(text.as_bytes(), "f.csv") {
        Ok(r) => format!("{:?} {:?} {:?}", r.time_s, r.columns, r.metadata),
        Err(e) => e.to_string(),
    };
    (blocks, whole)
}

#[test]
fn block_wise_read_gives_the_same_record_and_errors_as_in_memory() {
    // 97-byte blocks cut almost every line of these files at a different place; records
    // and error messages (with their line numbers) must be identical to the in-memory parse.
    let mut good = String::from("# meta\n\ntime_s,q_rad_s,alpha_rad\n");
    for i in 0..400 {
        let t = f64::from(i) * 0.01;
        good += &format!(
            "{t:.2},{:?},{:?}\n",
            (t * 1.3).sin() * 0.123,
            0.05 + t.cos() / 7.0
        );
    }
    let cases = [
        good.clone(),
        good.replace("\n1.20,", "\n1.2x,"),
        good.replace("\n2.50,", "\n2.50,1,2,3\n2.51,"),
        good.replace("\n3.00,", "\n2.00,"),
        good.clone() + "4.0,\"1.5\",2\n",
        good.replace("\n1.00,", "\n1.00,\"1\n\",2\n1.001,"),
        good.trim_end().to_string(),
        "time_s,q\n".to_string(),
        "# only\n".to_string(),
        good.replace("time_s", "t"),
    ];
    for (k, text) in cases.iter().enumerate() {
        let (blocks, whole) = both_ways(text);
        assert_eq!(blocks, whole, "case {k}");
        // Cases 1-3 carry an error late in the file, reported as `file:line:`.
        if [1, 2, 3].contains(&k) {
            assert!(blocks.starts_with("f.csv:"), "case {k}: {blocks}");
        }
    }
}

/// A sample far beyond what its column can hold (a corrupt 1e300, a negative airspeed) is refused naming
/// the file, the line, the column and the value in exponent form; an airspeed of 0 on every row is not a
/// record of flight. Values logged in another unit (degrees, knots) stay inside, for the unit warnings.
#[test]
fn implausible_values_are_refused_naming_line_column_and_value() {
    let good = "time_s,q_rad_s,airspeed_m_s,alpha_rad\n0,0.01,50,0.05\n0.05,0.02,50.1,0.06\n0.1,0.01,50.2,0.05\n";
    assert!(parse_csv_bytes(good.as_bytes(), "f.csv").is_ok());
    let refused = |text: &str| {
        parse_csv_bytes(text.as_bytes(), "f.csv")
            .unwrap_err()
            .to_string()
    };
    let huge = good.replace("0.05,0.02,", "0.05,1e300,");
    let e = refused(&huge);
    assert!(
        e.starts_with("f.csv:3: column `q_rad_s`: 1e300 is outside")
            && e.contains("-10000 to 10000"),
        "{e}"
    );
    let negative = good.replace(",50.1,", ",-50.1,");
    let e = refused(&negative);
    assert!(
        e.starts_with("f.csv:3: column `airspeed_m_s`: -50.1 is outside"),
        "{e}"
    );
    // A few m/s below zero is the noise of a signed root of the differential pressure at rest.
    let at_rest = good.replace(",50.1,", ",-2.0,");
    assert!(parse_csv_bytes(at_rest.as_bytes(), "f.csv").is_ok());
    let zero = good
        .replace(",50,", ",0,")
        .replace(",50.1,", ",0,")
        .replace(",50.2,", ",0.0,");
    let e = refused(&zero);
    assert!(
        e.contains("f.csv: column `airspeed_m_s` is 0 on every one of its 3 rows"),
        "{e}"
    );
    // Degrees and knots are a unit warning's business, not this check's.
    let degrees = good
        .replace(",0.05\n", ",3.0\n")
        .replace(",0.06\n", ",179.0\n");
    let rec = parse_csv_bytes(degrees.as_bytes(), "f.csv").unwrap();
    assert!(rec
        .warnings()
        .iter()
        .any(|w| w.kind == crate::data::WarningKind::LooksLikeDegrees));
    // Through a column map the range applies to the converted value, and the message gives both.
    let dir = tempfile::tempdir().unwrap();
    let map_path = dir.path().join("m.toml");
    fs::write(
        &map_path,
        "[columns]\nQ = { to = \"q_rad_s\", unit = \"deg/s\" }\n",
    )
    .unwrap();
    let map = ColumnMap::load(&map_path).unwrap();
    let in_deg = good
        .replace("q_rad_s", "Q")
        .replace("0.05,0.02,", "0.05,900000,");
    let e = parse_csv_bytes_mapped(in_deg.as_bytes(), "f.csv", Some(&map))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("`q_rad_s`: 900000 (15707.963267948966 after the column map's conversion)"),
        "{e}"
    );
}

#[test]
fn swar_digit_scan_reads_every_eight_digit_group() {
    for s in [
        "0.12345678",
        "-3.1234567890123456",
        "12.00000000",
        "0.99999999999",
    ] {
        let (v, end) = scan_cell(s.as_bytes(), 0);
        assert_eq!(end, s.len());
        assert_eq!(
            v.map(f64::to_bits),
            s.parse::<f64>().ok().map(f64::to_bits),
            "{s}"
        );
    }
    assert!(!eight_digits(u64::from_le_bytes(*b"1234567,")));
    assert!(!eight_digits(u64::from_le_bytes(*b"/1234567")));
    assert!(!eight_digits(u64::from_le_bytes(*b"123:4567")));
    assert_eq!(
        eight_digit_value(u64::from_le_bytes(*b"12345678")),
        12_345_678
    );
}
