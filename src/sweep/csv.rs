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

/// Reads `results.csv` text written by [`write_results`]: the parameter names and the rows.
/// `file` names the file in errors.
pub fn parse_results(text: &str, file: &str) -> Result<(Vec<String>, Vec<ResultRow>), SweepError> {
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
        let number = |column: usize| -> Result<f64, SweepError> {
            record[column].parse().map_err(|_| {
                SweepError(format!(
                    "{file}:{line}: {} {:?} is not a number",
                    header[column], &record[column]
                ))
            })
        };
        let point = record[0].parse().map_err(|_| {
            SweepError(format!(
                "{file}:{line}: point {:?} is not a number",
                &record[0]
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
    Ok((parameters, rows))
}

/// Merges shards' results (`(file name, text)` pairs): the same columns in every file, no point
/// twice; rows ordered by point.
pub fn merge_results(
    files: &[(String, String)],
) -> Result<(Vec<String>, Vec<ResultRow>), SweepError> {
    let mut merged: Option<(String, Vec<String>, Vec<String>)> = None;
    let mut rows: Vec<(ResultRow, String)> = Vec::new();
    for (file, text) in files {
        let (parameters, file_rows) = parse_results(text, file)?;
        let extra: Vec<String> = file_rows
            .first()
            .map(|r| r.extra.iter().map(|(n, _)| n.clone()).collect())
            .unwrap_or_default();
        match &merged {
            None => merged = Some((file.clone(), parameters, extra)),
            Some((first, p, _)) if *p != parameters => {
                return Err(SweepError(format!(
                    "{file}: parameters {parameters:?} differ from {first}'s {p:?}"
                )));
            }
            Some(_) => {}
        }
        rows.extend(file_rows.into_iter().map(|r| (r, file.clone())));
    }
    let Some((_, parameters, _)) = merged else {
        return Err(SweepError("nothing to merge: no results.csv given".into()));
    };
    rows.sort_by_key(|(r, _)| r.point);
    for pair in rows.windows(2) {
        if pair[0].0.point == pair[1].0.point {
            return Err(SweepError(format!(
                "point {} is in both {} and {}",
                pair[0].0.point, pair[0].1, pair[1].1
            )));
        }
    }
    Ok((parameters, rows.into_iter().map(|(r, _)| r).collect()))
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
        let (p, back) = parse_results(&text, "r.csv").expect("parse");
        assert_eq!(p, parameters);
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
        let (_, rows) =
            merge_results(&[("1.csv".into(), one.clone()), ("2.csv".into(), two)]).unwrap();
        assert_eq!(rows.iter().map(|r| r.point).collect::<Vec<_>>(), [0, 1, 2]);
        let err = merge_results(&[("1.csv".into(), one.clone()), ("x.csv".into(), one)])
            .expect_err("duplicate points");
        assert!(err.0.contains("point 0"), "{err}");
        let other = write_results(&["c".to_string()], &[]).unwrap();
        let err = merge_results(&[
            ("1.csv".into(), write_results(&parameters, &[]).unwrap()),
            ("2.csv".into(), other),
        ])
        .expect_err("different parameters");
        assert!(err.0.contains("2.csv"), "{err}");
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
    }
}
