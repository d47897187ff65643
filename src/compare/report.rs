//! Comparing a folder of references with a folder of captures (beside the pipeline: comparison):
//! images paired by name ([`pair_names`]), one [`Row`] per pair with its [`Comparison`], worst
//! first, and the report written as JSON and as an HTML page (reference | heat map | capture, the
//! figures, the verdict; missing and extra files listed). The files are read and written by the
//! caller (`pelage compare REF_DIR TEST_DIR -o REPORT_DIR`); this module only decides and formats.
//!
//! The page fits its window: the table is the page's width, a row's three images sit side by
//! side when each fits at three quarters of its size or more and wrap under each other when
//! they do not, and an image wider than its place is scaled down (`max-width: 100%`, the
//! height following). Images narrower than
//! [`MIN_SHOWN_WIDTH`] are zoomed by a whole factor, pixelated, so that their pixels stay sharp.

use super::{Comparison, Tolerance};
use serde::Serialize;
use std::collections::BTreeMap;

/// Narrowest a reference or capture is shown, CSS pixels: a narrower one is zoomed by the whole
/// factor that brings it closest to this, at most ×4 ([`zoom`]).
pub const MIN_SHOWN_WIDTH: u32 = 200;

/// The whole factor an image `width` pixels wide is zoomed by on the report page.
pub fn zoom(width: u32) -> u32 {
    (MIN_SHOWN_WIDTH / width.max(1)).clamp(1, 4)
}

/// File extensions read as images (lower case).
pub const IMAGE_EXTENSIONS: [&str; 7] = ["png", "exr", "jpg", "jpeg", "bmp", "gif", "webp"];

/// Whether `name` is an image file by its extension (any case), not hidden.
pub fn is_image_name(name: &str) -> bool {
    !name.starts_with('.')
        && name.rsplit_once('.').is_some_and(|(stem, ext)| {
            !stem.is_empty() && IMAGE_EXTENSIONS.contains(&ext.to_ascii_lowercase().as_str())
        })
}

/// The name an image is paired by: its file name without the extension.
pub fn stem(name: &str) -> &str {
    name.rsplit_once('.').map_or(name, |(s, _)| s)
}

/// References and captures paired by [`stem`] (so `torus.png` pairs with `torus.exr`).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Pairing {
    /// `(stem, reference file, capture file)`, by stem.
    pub pairs: Vec<(String, String, String)>,
    /// References with no capture of their name.
    pub missing: Vec<String>,
    /// Captures with no reference of their name.
    pub extra: Vec<String>,
}

/// Pairs the image files of two folders by stem. Two images of one stem in one folder
/// (`a.png` and `a.exr`) are ambiguous: an error naming them.
pub fn pair_names(references: &[String], captures: &[String]) -> Result<Pairing, String> {
    fn by_stem(names: &[String], folder: &str) -> Result<BTreeMap<String, String>, String> {
        let mut map: BTreeMap<String, String> = BTreeMap::new();
        for name in names.iter().filter(|n| is_image_name(n)) {
            if let Some(other) = map.insert(stem(name).to_string(), name.clone()) {
                return Err(format!(
                    "{folder}: {other} and {name} have the same name: which is the image?"
                ));
            }
        }
        Ok(map)
    }
    let refs = by_stem(references, "reference folder")?;
    let mut caps = by_stem(captures, "capture folder")?;
    let mut pairing = Pairing::default();
    for (s, r) in refs {
        match caps.remove(&s) {
            Some(c) => pairing.pairs.push((s, r, c)),
            None => pairing.missing.push(r),
        }
    }
    pairing.extra = caps.into_values().collect();
    pairing.extra.sort();
    Ok(pairing)
}

/// The verdict of one row.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    /// The images could not be compared (unreadable, sizes differ).
    Error,
    /// Outside the tolerance.
    Fail,
    /// Within the tolerance.
    Pass,
}

/// One pair of the report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Row {
    /// The stem both files share.
    pub name: String,
    /// The reference's file name.
    pub reference: String,
    /// The capture's file name.
    pub capture: String,
    /// The verdict.
    pub verdict: Verdict,
    /// Why the images could not be compared (for [`Verdict::Error`]).
    pub error: Option<String>,
    /// The figures (absent for [`Verdict::Error`]).
    pub comparison: Option<Comparison>,
    /// The report's copies of the images, relative to the report folder: reference, heat
    /// map, capture, FLIP map (absent for [`Verdict::Error`]).
    pub images: Option<[String; 4]>,
}

impl Row {
    /// How bad the row is, for sorting worst first: errors, then failures, then passes; within
    /// each, the larger FLIP mean, then the more pixels over the threshold, then the name.
    fn badness(&self) -> (Verdict, std::cmp::Reverse<u32>, std::cmp::Reverse<u64>) {
        let (flip, over) = self.comparison.as_ref().map_or((0, 0), |c| {
            (c.flip.mean.max(0.0).to_bits(), c.over_threshold)
        });
        (
            self.verdict,
            std::cmp::Reverse(flip),
            std::cmp::Reverse(over),
        )
    }
}

/// The whole report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    /// The reference folder as given.
    pub reference_folder: String,
    /// The capture folder as given.
    pub capture_folder: String,
    /// The tolerance every pair was judged by.
    pub tolerance: Tolerance,
    /// The criteria it checks.
    pub checked: Vec<String>,
    /// One row per pair, worst first.
    pub rows: Vec<Row>,
    /// References with no capture (each a failure).
    pub missing: Vec<String>,
    /// Captures with no reference (listed, not judged).
    pub extra: Vec<String>,
    /// Pairs within tolerance.
    pub passed: usize,
    /// Pairs outside tolerance.
    pub failed: usize,
    /// Pairs that could not be compared.
    pub errors: usize,
}

impl Report {
    /// The report of `rows` (sorted here, worst first).
    pub fn new(
        reference_folder: String,
        capture_folder: String,
        tolerance: &Tolerance,
        mut rows: Vec<Row>,
        missing: Vec<String>,
        extra: Vec<String>,
    ) -> Self {
        rows.sort_by(|a, b| {
            a.badness()
                .cmp(&b.badness())
                .then_with(|| a.name.cmp(&b.name))
        });
        let count = |v: Verdict| rows.iter().filter(|r| r.verdict == v).count();
        Report {
            reference_folder,
            capture_folder,
            tolerance: tolerance.clone(),
            checked: tolerance.criteria(),
            passed: count(Verdict::Pass),
            failed: count(Verdict::Fail),
            errors: count(Verdict::Error),
            rows,
            missing,
            extra,
        }
    }

    /// The exit status, as for one pair: 2 when a pair could not be compared, 1 when one is
    /// outside tolerance or a reference has no capture, 0 otherwise.
    pub fn exit_status(&self) -> u8 {
        if self.errors > 0 {
            2
        } else if self.failed > 0 || !self.missing.is_empty() {
            1
        } else {
            0
        }
    }

    /// One line: the counts.
    pub fn summary(&self) -> String {
        format!(
            "{} of {} pairs within tolerance, {} outside, {} not comparable; {} missing, {} extra",
            self.passed,
            self.rows.len(),
            self.failed,
            self.errors,
            self.missing.len(),
            self.extra.len()
        )
    }

    /// The report as a self-contained HTML page (images linked from the report folder).
    pub fn html(&self) -> String {
        let mut h = String::new();
        h.push_str(concat!(
            "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n",
            "<title>pelage compare report</title>\n<style>\n",
            "body{font-family:sans-serif;margin:1.5em;background:#fafafa;color:#222}\n",
            "code{overflow-wrap:anywhere}\n",
            "table{border-collapse:collapse;width:100%}\n",
            "td,th{border:1px solid #ccc;padding:6px;vertical-align:top;text-align:left}\n",
            "th{background:#eee}\n",
            "td.name{overflow-wrap:anywhere;min-width:7em}\n",
            "td.images{width:100%}\n",
            "div.images{display:flex;flex-wrap:wrap;gap:8px 12px;align-items:flex-start}\n",
            "figure{margin:0;min-width:0;max-width:100%}\n",
            "figure img{width:100%}\n",
            "figcaption{font-size:small;color:#555;margin-top:2px}\n",
            "img{display:block;max-width:100%;height:auto}\n",
            "img.zoomed{image-rendering:pixelated}\n",
            "tr.fail td.verdict{background:#f8d0d0;font-weight:bold}\n",
            "tr.error td.verdict{background:#f0b0f0;font-weight:bold}\n",
            "tr.pass td.verdict{background:#d0f0d0}\n",
            "td.figures{font-family:monospace;white-space:pre-wrap;overflow-wrap:anywhere}\n",
            "td.figures div{width:17em}\n",
            "</style>\n</head>\n<body>\n<h1>pelage compare report</h1>\n"
        ));
        h.push_str(&format!(
            "<p id=\"summary\">{}</p>\n<p>References: <code>{}</code>; captures: <code>{}</code>.</p>\n",
            escape(&self.summary()),
            escape(&self.reference_folder),
            escape(&self.capture_folder)
        ));
        h.push_str(&format!(
            "<p>Tolerance <code>{}</code>, checking: {}.</p>\n",
            escape(&self.tolerance.to_string()),
            if self.checked.is_empty() {
                "nothing".to_string()
            } else {
                escape(&self.checked.join("; "))
            }
        ));
        for (id, title, names) in [
            (
                "missing",
                "References without a capture (failures)",
                &self.missing,
            ),
            (
                "extra",
                "Captures without a reference (not judged)",
                &self.extra,
            ),
        ] {
            if !names.is_empty() {
                h.push_str(&format!("<h2>{title}</h2>\n<ul id=\"{id}\">\n"));
                for n in names {
                    h.push_str(&format!("<li>{}</li>\n", escape(n)));
                }
                h.push_str("</ul>\n");
            }
        }
        h.push_str(concat!(
            "<table id=\"pairs\">\n<tr><th>#</th><th>image</th><th>verdict</th>",
            "<th>reference | heat map | capture</th><th>figures</th></tr>\n"
        ));
        for (i, row) in self.rows.iter().enumerate() {
            let class = match row.verdict {
                Verdict::Pass => "pass",
                Verdict::Fail => "fail",
                Verdict::Error => "error",
            };
            h.push_str(&format!(
                "<tr class=\"row {class}\" data-name=\"{}\"><td>{}</td><td class=\"name\">{}<br><small>{} | {}</small></td><td class=\"verdict\">{}</td>",
                escape(&row.name),
                i + 1,
                escape(&row.name),
                escape(&row.reference),
                escape(&row.capture),
                class.to_uppercase()
            ));
            match (&row.images, &row.comparison) {
                (Some([r, heat, c, flip]), Some(cmp)) => {
                    let (w, hh) = (cmp.width, cmp.height);
                    let z = zoom(w);
                    let zoomed = if z > 1 {
                        format!(" (×{z})")
                    } else {
                        String::new()
                    };
                    // The heat map carries its legend: at least LEGEND_MIN_WIDTH wide, taller
                    // by LEGEND_HEIGHT; shown at its own size, so its legend reads as drawn.
                    let heat_size = (
                        w.max(super::legend::LEGEND_MIN_WIDTH),
                        hh + super::legend::LEGEND_HEIGHT,
                    );
                    h.push_str("<td class=\"images\"><div class=\"images\">");
                    for (src, alt, (fw, fh), fz, caption) in [
                        (r, "reference", (w, hh), z, format!("reference{zoomed}")),
                        (
                            heat,
                            "heat map",
                            heat_size,
                            1,
                            format!("heat map · <a href=\"{}\">FLIP map</a>", escape(flip)),
                        ),
                        (c, "capture", (w, hh), z, format!("capture{zoomed}")),
                    ] {
                        // Shown at most at its (zoomed) size; side by side with the others while
                        // each keeps three quarters of it, else on a line of its own.
                        let (sw, sh) = (fw * fz, fh * fz);
                        h.push_str(&format!(
                            "<figure style=\"flex:1 1 {basis}px;max-width:{sw}px\"><a href=\"{0}\"><img src=\"{0}\" alt=\"{1} of {2}\" width=\"{sw}\" height=\"{sh}\"{3}></a><figcaption>{4}</figcaption></figure>",
                            escape(src),
                            alt,
                            escape(&row.name),
                            if fz > 1 { " class=\"zoomed\"" } else { "" },
                            caption,
                            basis = sw * 3 / 4,
                        ));
                    }
                    h.push_str("</div></td>");
                    h.push_str(&format!(
                        "<td class=\"figures\"><div>{}</div></td>",
                        escape(&figures(cmp))
                    ));
                }
                _ => h.push_str(&format!(
                    "<td colspan=\"2\">{}</td>",
                    escape(row.error.as_deref().unwrap_or("not compared"))
                )),
            }
            h.push_str("</tr>\n");
        }
        h.push_str("</table>\n");
        // The page says, once loaded, how many of its images decoded: a check for the report's
        // test in a headless browser, and a hint to a reader whose images did not load.
        h.push_str(concat!(
            "<p id=\"loaded\"></p>\n<script>\nwindow.addEventListener('load', () => {\n",
            "  const images = Array.from(document.images);\n",
            "  const ok = images.filter(i => i.complete && i.naturalWidth > 0).length;\n",
            "  document.body.dataset.imagesLoaded = ok + '/' + images.length;\n",
            "  document.getElementById('loaded').textContent = ok + ' of ' + images.length + ' images loaded';\n",
            "  // How far the page runs past the window's right edge (0: it fits), and how many rows\n",
            "  // show their images side by side on one line.\n",
            "  const root = document.documentElement;\n",
            "  document.body.dataset.overflow = Math.max(0, root.scrollWidth - root.clientWidth);\n",
            "  const rows = Array.from(document.querySelectorAll('div.images'));\n",
            "  const oneLine = rows.filter(d => new Set(Array.from(d.children, f => f.offsetTop)).size === 1);\n",
            "  document.body.dataset.sideBySide = oneLine.length + '/' + rows.length;\n",
            "});\n</script>\n</body>\n</html>\n"
        ));
        h
    }
}

/// The figures of a comparison, a few lines for the report.
fn figures(c: &Comparison) -> String {
    let mut s = format!(
        "exact     {:.3}%\nmax error {}/{}/{}/{}\nPSNR      {}\nover {:>3}  {:.4}%\nFLIP mean {:.5}\nFLIP p99  {:.5}",
        100.0 * c.exact_pixels as f64 / c.pixels as f64,
        c.max_abs_error[0],
        c.max_abs_error[1],
        c.max_abs_error[2],
        c.max_abs_error[3],
        c.psnr,
        c.tolerance.channel_threshold,
        100.0 * c.over_fraction(),
        c.flip.mean,
        c.flip.p99
    );
    for f in &c.failures {
        s.push_str("\n✗ ");
        s.push_str(f);
    }
    s
}

/// `text` with the characters HTML gives a meaning escaped.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            _ => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(list: &[&str]) -> Vec<String> {
        list.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn images_pair_by_stem_and_the_rest_is_listed() {
        let p = pair_names(
            &names(&["b.png", "a.png", "c.png", "notes.txt", ".hidden.png"]),
            &names(&["a.exr", "b.png", "d.JPG", "README"]),
        )
        .unwrap();
        assert_eq!(
            p.pairs,
            vec![
                ("a".into(), "a.png".into(), "a.exr".into()),
                ("b".into(), "b.png".into(), "b.png".into())
            ]
        );
        assert_eq!(p.missing, names(&["c.png"]));
        assert_eq!(p.extra, names(&["d.JPG"]));
        let e = pair_names(&names(&["a.png", "a.exr"]), &[]).unwrap_err();
        assert!(e.contains("a.png") && e.contains("a.exr"), "{e}");
    }

    #[test]
    fn small_images_are_zoomed_by_a_whole_factor() {
        assert_eq!(zoom(96), 2);
        assert_eq!(zoom(64), 3);
        assert_eq!(zoom(10), 4);
        assert_eq!(zoom(0), 4);
        assert_eq!(zoom(200), 1);
        assert_eq!(zoom(1366), 1);
    }

    #[test]
    fn html_escapes_names() {
        assert_eq!(escape("<a & \"b\">'"), "&lt;a &amp; &quot;b&quot;&gt;&#39;");
    }
}
