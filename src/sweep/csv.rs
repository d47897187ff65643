//! `results.csv` (beside the pipeline: sweeps): one row per sweep point, `point` first, then the
//! parameters in order, then the measurements. Shards write the same header; merging checks it and
//! orders rows by point.

use super::SweepError;

/// One row of `results.csv`.
#[derive(Clone, Debug, PartialEq)]
pub struct ResultRow {
    /// The point's number in the whole sweep.
    pub point: usize,
    /// The parameter values, in parameter order.
    pub values: Vec<String>,
    /// Baking time, milliseconds.
    pub bake_ms: f64,
    /// Median frame time, milliseconds.
    pub median_frame_ms: f64,
    /// Fastest frame, milliseconds.
    pub min_frame_ms: f64,
    /// Slowest frame, milliseconds.
    pub max_frame_ms: f64,
    /// Frames per second at the median frame time.
    pub fps: f64,
    /// Fragments shaded per frame.
    pub fragments_shaded: u64,
    /// Extra columns (name, value) after the standard ones, the same names on every row.
    pub extra: Vec<(String, String)>,
}

/// The measurement columns after the parameters.
pub const MEASUREMENT_COLUMNS: &[&str] = &[
    "bake_ms",
    "median_frame_ms",
    "min_frame_ms",
    "max_frame_ms",
    "fps",
    "fragments_shaded",
];

/// Writes the rows as CSV text (RFC 4180 quoting), header first.
pub fn write_results(parameters: &[String], rows: &[ResultRow]) -> Result<String, SweepError> {
    let failed = |e: csv::Error| SweepError(format!("cannot write results.csv: {e}"));
    let mut writer = csv::Writer::from_writer(Vec::new());
    let extra_names: Vec<&str> = rows
        .first()
        .map(|r| r.extra.iter().map(|(n, _)| n.as_str()).collect())
        .unwrap_or_default();
    let header = std::iter::once("point")
        .chain(parameters.iter().map(String::as_str))
        .chain(MEASUREMENT_COLUMNS.iter().copied())
        .chain(extra_names.iter().copied());
    writer.write_record(header).map_err(failed)?;
    for row in rows {
        let mut record = vec![row.point.to_string()];
        record.extend(row.values.iter().cloned());
        record.extend([
            format!("{:.3}", row.bake_ms),
            format!("{:.3}", row.median_frame_ms),
            format!("{:.3}", row.min_frame_ms),
            format!("{:.3}", row.max_frame_ms),
            format!("{:.3}", row.fps),
            row.fragments_shaded.to_string(),
        ]);
        record.extend(row.extra.iter().map(|(_, v)| v.clone()));
        writer.write_record(&record).map_err(failed)?;
    }
    let bytes = writer
        .into_inner()
        .map_err(|e| SweepError(format!("cannot write results.csv: {e}")))?;
    String::from_utf8(bytes).map_err(|e| SweepError(format!("results.csv: {e}")))
}

/// A `results.csv` as read: its columns and rows.
#[derive(Clone, Debug, PartialEq)]
pub struct Results {
    /// The parameter columns, in order.
    pub parameters: Vec<String>,
    /// The extra columns after the measurements (`--against-oracle`'s metrics), in order.
    pub extra_columns: Vec<String>,
    /// The rows, in file order.
    pub rows: Vec<ResultRow>,
}

/// Reads `results.csv` text written by [`write_results`]. `file` names the file in errors.
/// Measurements must be finite and not negative, points below [`super::MAX_POINTS`] and at most
/// that many rows: a hand-edited value that no sweep writes is refused here, naming its line,
/// rather than sizing a plot or a loop.
pub fn parse_results(text: &str, file: &str) -> Result<Results, SweepError> {
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    let header: Vec<String> = reader
        .headers()
        .map_err(|e| SweepError(format!("{file}: {e}")))?
        .iter()
        .map(str::to_string)
        .collect();
    let first_measure = header
        .iter()
        .position(|h| h == MEASUREMENT_COLUMNS[0])
        .filter(|&i| {
            header.first().map(String::as_str) == Some("point")
                && header.len() >= i + MEASUREMENT_COLUMNS.len()
                && header[i..i + MEASUREMENT_COLUMNS.len()] == *MEASUREMENT_COLUMNS
        })
        .ok_or_else(|| {
            SweepError(format!(
                "{file}:1: not a pelage results.csv (expected point, the parameters, then {})",
                MEASUREMENT_COLUMNS.join(", ")
            ))
        })?;
    let parameters = header[1..first_measure].to_vec();
    let extra_names = &header[first_measure + MEASUREMENT_COLUMNS.len()..];
    let mut rows = Vec::new();
    for (i, record) in reader.records().enumerate() {
        let line = i + 2;
        let record = record.map_err(|e| SweepError(format!("{file}:{line}: {e}")))?;
        if record.len() != header.len() {
            return Err(SweepError(format!(
                "{file}:{line}: {} fields, the header has {}",
                record.len(),
                header.len()
            )));
        }
        if rows.len() == super::MAX_POINTS {
            return Err(SweepError(format!(
                "{file}:{line}: more than {} rows (a sweep has at most as many points)",
                super::MAX_POINTS
            )));
        }
        let number = |column: usize| -> Result<f64, SweepError> {
            record[column]
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && *v >= 0.0)
                .ok_or_else(|| {
                    SweepError(format!(
                        "{file}:{line}: {} {:?} is not a finite number ≥ 0",
                        header[column], &record[column]
                    ))
                })
        };
        let point = record[0]
            .parse::<usize>()
            .ok()
            .filter(|&p| p < super::MAX_POINTS)
            .ok_or_else(|| {
                SweepError(format!(
                    "{file}:{line}: point {:?} is not a point number (0 to {})",
                    &record[0],
                    super::MAX_POINTS - 1
                ))
            })?;
        let m = first_measure;
        rows.push(ResultRow {
            point,
            values: (1..m).map(|c| record[c].to_string()).collect(),
            bake_ms: number(m)?,
            median_frame_ms: number(m + 1)?,
            min_frame_ms: number(m + 2)?,
            max_frame_ms: number(m + 3)?,
            fps: number(m + 4)?,
            fragments_shaded: record[m + 5].parse().map_err(|_| {
                SweepError(format!(
                    "{file}:{line}: fragments_shaded {:?} is not a whole number",
                    &record[m + 5]
                ))
            })?,
            extra: extra_names
                .iter()
                .zip(record.iter().skip(m + MEASUREMENT_COLUMNS.len()))
                .map(|(n, v)| (n.clone(), v.to_string()))
                .collect(),
        });
    }
    Ok(Results {
        parameters,
        extra_columns: extra_names.to_vec(),
        rows,
    })
}

/// Merges shards' results (`(file name, text)` pairs): the same columns in every file (the
/// parameters and the extra columns alike, so that no value is merged under another column's
/// name), no point twice; rows ordered by point.
pub fn merge_results(files: &[(String, String)]) -> Result<Results, SweepError> {
    let mut merged: Option<(String, Results)> = None;
    let mut origins: Vec<(usize, usize)> = Vec::new();
    for (index, (file, text)) in files.iter().enumerate() {
        let results = parse_results(text, file)?;
        origins.extend(results.rows.iter().map(|r| (r.point, index)));
        match &mut merged {
            None => merged = Some((file.clone(), results)),
            Some((first, m)) => {
                if m.parameters != results.parameters {
                    return Err(SweepError(format!(
                        "{file}: parameters {:?} differ from {first}'s {:?}",
                        results.parameters, m.parameters
                    )));
                }
                if m.extra_columns != results.extra_columns {
                    return Err(SweepError(format!(
                        "{file}: columns after the measurements {:?} differ from {first}'s {:?} \
                         (shards of one sweep are run with the same options)",
                        results.extra_columns, m.extra_columns
                    )));
                }
                m.rows.extend(results.rows);
            }
        }
    }
    let Some((_, mut merged)) = merged else {
        return Err(SweepError("nothing to merge: no results.csv given".into()));
    };
    origins.sort_unstable();
    for pair in origins.windows(2) {
        if pair[0].0 == pair[1].0 {
            return Err(SweepError(format!(
                "point {} is in both {} and {}",
                pair[0].0, files[pair[0].1].0, files[pair[1].1].0
            )));
        }
    }
    merged.rows.sort_by_key(|r| r.point);
    Ok(merged)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(point: usize, value: &str, fps: f64) -> ResultRow {
        ResultRow {
            point,
            values: vec![value.to_string(), "[1, 0, 0]".to_string()],
            bake_ms: 12.5,
            median_frame_ms: 1000.0 / fps,
            min_frame_ms: 900.0 / fps,
            max_frame_ms: 1100.0 / fps,
            fps,
            fragments_shaded: 1234,
            extra: vec![("psnr".into(), "inf".into())],
        }
    }

    #[test]
    fn results_round_trip_through_csv() {
        let parameters = vec![
            "number_of_shells".to_string(),
            "light.direction".to_string(),
        ];
        let rows = vec![row(0, "10", 8.0), row(1, "20", 4.0)];
        let text = write_results(&parameters, &rows).expect("csv");
        assert!(text.starts_with("point,number_of_shells,light.direction,bake_ms,"));
        assert!(text.contains("\"[1, 0, 0]\""));
        let Results {
            parameters: p,
            extra_columns,
            rows: back,
        } = parse_results(&text, "r.csv").expect("parse");
        assert_eq!(p, parameters);
        assert_eq!(extra_columns, ["psnr"]);
        assert_eq!(back.len(), 2);
        assert_eq!(back[1].values, rows[1].values);
        assert_eq!(back[1].fps, 4.0);
        assert_eq!(back[0].extra, rows[0].extra);
    }

    #[test]
    fn shards_merge_in_point_order_and_clash_on_duplicates() {
        let parameters = vec!["a".to_string(), "b".to_string()];
        let one = write_results(&parameters, &[row(0, "1", 2.0), row(2, "3", 2.0)]).unwrap();
        let two = write_results(&parameters, &[row(1, "2", 2.0)]).unwrap();
        let rows = merge_results(&[("1.csv".into(), one.clone()), ("2.csv".into(), two)])
            .unwrap()
            .rows;
        assert_eq!(rows.iter().map(|r| r.point).collect::<Vec<_>>(), [0, 1, 2]);
        let err = merge_results(&[("1.csv".into(), one.clone()), ("x.csv".into(), one.clone())])
            .expect_err("duplicate points");
        assert!(err.0.contains("point 0"), "{err}");
        let other = write_results(&["c".to_string()], &[]).unwrap();
        let err = merge_results(&[
            ("1.csv".into(), write_results(&parameters, &[]).unwrap()),
            ("2.csv".into(), other),
        ])
        .expect_err("different parameters");
        assert!(err.0.contains("2.csv"), "{err}");
        // The same parameters but other extra columns: FLIP values are not merged as PSNR.
        let mut flip = row(1, "2", 2.0);
        flip.extra = vec![("flip_mean".into(), "0.01".into())];
        let three = write_results(&parameters, &[flip]).unwrap();
        let err = merge_results(&[("1.csv".into(), one.clone()), ("3.csv".into(), three)])
            .expect_err("different extra columns");
        assert!(
            err.0.contains("3.csv") && err.0.contains("flip_mean"),
            "{err}"
        );
        // A shard without rows still has its header's columns checked.
        let empty = write_results(&parameters, &[]).unwrap();
        let err = merge_results(&[("1.csv".into(), one), ("4.csv".into(), empty)])
            .expect_err("no extra columns");
        assert!(err.0.contains("4.csv"), "{err}");
    }

    #[test]
    fn malformed_results_name_file_and_line() {
        let err = parse_results("a,b\n1,2\n", "bad.csv").expect_err("not ours");
        assert!(err.0.starts_with("bad.csv:1:"), "{err}");
        let text = write_results(&["a".into(), "b".into()], &[row(0, "1", 2.0)])
            .unwrap()
            .replace("1234", "many");
        let err = parse_results(&text, "r.csv").expect_err("bad number");
        assert!(err.0.starts_with("r.csv:2:"), "{err}");
        let good = write_results(&["a".into(), "b".into()], &[row(0, "1", 2.0)]).unwrap();
        for (from, to) in [
            (",2.000,", ",1e308,"),
            (",2.000,", ",inf,"),
            (",2.000,", ",NaN,"),
            (",2.000,", ",-2,"),
            ("\n0,", "\n18446744073709551615,"),
            ("\n0,", "\n100000,"),
        ] {
            let text = good.replacen(from, to, 1);
            assert_ne!(text, good, "{from} is in {good}");
            if to == ",1e308," {
                // Finite: read, and left to the plot to place.
                parse_results(&text, "r.csv").expect("finite");
                continue;
            }
            let err = parse_results(&text, "r.csv").expect_err(to);
            assert!(err.0.starts_with("r.csv:2:"), "{to}: {err}");
        }
    }
}
