//! Debug renders of the thesis's strand-construction figures 3.2–3.7, drawn from the real fur
//! code: one strand from [`generate_strands`], its cone segments from the baker's own cone chain
//! (`strand_cones`, facet tangents, slab clipping), and its shell slices from [`bake_shells`].
//! Nothing here is a separate model of a strand; a figure only chooses parameters, a camera and
//! colours.
//!
//! Every figure is [`DIAGRAM_WIDTH`] × [`DIAGRAM_HEIGHT`] RGBA, opaque, drawn with tiny-skia
//! (anti-aliased fills and strokes) and labelled in the embedded DejaVu Sans ([`crate::font`]),
//! mixed case with the real symbols (`i·H/N`, `×4`, `30°`). Labels are placed by measuring
//! them ([`font::text_width`]) and kept clear of the drawing and of each other (a test checks
//! every figure). The bytes depend only on the figure and the [`DiagramOptions`] (seed and
//! resolutions): the same on every run.
//!
//! The strand of every figure is strand 0 of the generator for the options' seed, with the
//! figure's parameters (listed at [`Figure`]), turned about the vertical so that it leans along
//! `+x` and moved so that its root is at `(0.1, 0.5, 0)` in the tile. A rigid motion: its shape,
//! cones and jitter are the generator's. Views: *side* is the orthographic view along `+y`
//! (`x` right, `z` up); *oblique* is the same view tilted down by an elevation angle, so that
//! rings around the strand show as ellipses; *top* looks down `−z` (`x` right, `y` up) at the
//! baked texels, one square per texel.

use glam::{Vec2, Vec3};
use image::RgbaImage;
use tiny_skia::{Color, FillRule, Paint, PathBuilder, Pixmap, Rect, Stroke, StrokeDash, Transform};

use super::bake::{ShellLayer, bake_shells, clip_to_slab, cones_of};
use super::cone::ConeSegment;
use super::params::{FurError, FurParams};
use super::strand::{Strand, bezier_point, generate_strands};
use crate::font;

/// Width of every figure, pixels.
pub const DIAGRAM_WIDTH: u32 = 960;
/// Height of every figure, pixels.
pub const DIAGRAM_HEIGHT: u32 = 540;
/// Largest `strand_resolution` and `circle_resolution` a figure accepts: finer cones than this
/// draw more facets than the figure has pixels for.
pub const MAX_DIAGRAM_RESOLUTION: u32 = 256;
/// Shell layers of figures 3.6 and 3.7.
pub const DIAGRAM_SHELLS: u32 = 6;

/// Where the strand's root is put in the tile (see the module docs).
const ROOT: Vec3 = Vec3::new(0.1, 0.5, 0.0);

/// A thesis figure of strand construction (thesis 3.1.1–3.1.2).
///
/// Parameters shared by every figure: one strand, height 1 tile unit, slope 30°, curl 0.1,
/// jitter 0.1 (the generator's randomness, from the seed), thickness jitter 0, circle
/// resolution 10 (the thesis's base value); the rest as listed per figure. 3.6 and 3.7 bake
/// [`DIAGRAM_SHELLS`] layers without supersampling (so each texel shows one facet's tangent) and
/// with Gaussian σ = 1000 (alpha = coverage).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Figure {
    /// 3.2 "A strand produced by Bézier curve": side view of the curve, its control polygon and
    /// the four points (root, control near the middle, control near the tip, tip), with the
    /// `strand_resolution` (default 20) sample points.
    Strand,
    /// 3.3 "Encapsulation of a Bézier spline": oblique view of the cone chain (radius 0.08 at the
    /// root, 0.03 at the tip; strand resolution 8 by default) as a wireframe around the curve
    /// and as shaded facets.
    Cones,
    /// 3.4 "A fur encapsulated with our spherical cones to produce thick and thin fur": the same
    /// strand with radii 0.08 → 0.03 and 0.025 → 0.008, at one scale.
    Thickness,
    /// 3.5 "A normal sloped and a higher sloped fur": the same draws at slope 20° (the default)
    /// and 50°, side view at one scale, with the horizontal run from root to tip marked.
    Slope,
    /// 3.6 "A view of the shells from the top and from the sides": the strand sliced at the
    /// shell heights `i·H/N`, each slice in its layer's colour, from the side; the baked layers
    /// from the top (texture resolution 64); and the baked layers from the side, each flat on its
    /// shell.
    Shells,
    /// 3.7 "Inner and the outer part of a strand": an exploded oblique view of the slices with
    /// the cut faces (inner parts) in magenta; the top view of layer 3 (texture resolution 96,
    /// radius 0.12 → 0.01) with inner and outer texels told apart; and the tangents the baker
    /// stores there, as stored and with the contrast stretched ×4: the inner texels carry the
    /// tangent of the outer facet at their angle.
    InnerOuter,
}

impl Figure {
    /// Every figure, in thesis order.
    pub const ALL: [Figure; 6] = [
        Figure::Strand,
        Figure::Cones,
        Figure::Thickness,
        Figure::Slope,
        Figure::Shells,
        Figure::InnerOuter,
    ];

    /// The thesis's figure number, e.g. `"3.4"`.
    pub fn number(self) -> &'static str {
        match self {
            Figure::Strand => "3.2",
            Figure::Cones => "3.3",
            Figure::Thickness => "3.4",
            Figure::Slope => "3.5",
            Figure::Shells => "3.6",
            Figure::InnerOuter => "3.7",
        }
    }

    /// The thesis's caption, shortened where it is long.
    pub fn caption(self) -> &'static str {
        match self {
            Figure::Strand => "A strand produced by a Bézier curve",
            Figure::Cones => "Encapsulation of a Bézier spline in circular cones",
            Figure::Thickness => "Thick and thin fur: base and tip thickness",
            Figure::Slope => "A normal sloped and a higher sloped fur",
            Figure::Shells => "A view of the shells from the top and from the side",
            Figure::InnerOuter => "Inner and outer part of a sliced strand",
        }
    }

    /// The file name `pelage diagram --all` writes, e.g. `fig-3-4.png`.
    pub fn file_name(self) -> String {
        format!("fig-{}.png", self.number().replace('.', "-"))
    }

    /// The figure named `name`: its number (`3.4`), with `-` for the dot (`3-4`), optionally
    /// after `fig-` or `fig` (`fig-3-4`, `fig3.4`). `None` for anything else.
    pub fn parse(name: &str) -> Option<Figure> {
        let lower = name.trim().to_ascii_lowercase();
        let rest = lower
            .strip_prefix("figure")
            .or_else(|| lower.strip_prefix("fig"))
            .unwrap_or(&lower);
        let rest = rest.trim_start_matches(['-', '_', ' ']).replace('-', ".");
        Figure::ALL.into_iter().find(|f| f.number() == rest)
    }
}

/// What a figure may be asked to change.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DiagramOptions {
    /// Seed of the strand generator (`pelage diagram` uses the embedded scene's, 1234).
    pub seed: u32,
    /// Bézier segments per strand, instead of the figure's default (1..=[`MAX_DIAGRAM_RESOLUTION`]).
    pub strand_resolution: Option<u32>,
    /// Facets around each cone, instead of 10 (3..=[`MAX_DIAGRAM_RESOLUTION`]).
    pub circle_resolution: Option<u32>,
}

impl DiagramOptions {
    /// The figure defaults with `seed`.
    pub fn new(seed: u32) -> Self {
        DiagramOptions {
            seed,
            strand_resolution: None,
            circle_resolution: None,
        }
    }
}

/// Draws `figure`. Fails only on resolutions out of range (the error names the parameter).
pub fn draw_diagram(figure: Figure, options: &DiagramOptions) -> Result<RgbaImage, FurError> {
    Ok(render(figure, options)?.finish())
}

// ---------------------------------------------------------------------------------------------
// Colours.

type Rgb = [u8; 3];
const BACKGROUND: Rgb = [250, 248, 244];
const INK: Rgb = [40, 40, 40];
const MUTED: Rgb = [110, 110, 110];
const GROUND: Rgb = [160, 160, 160];
const GUIDE: Rgb = [150, 150, 150];
const CURVE: Rgb = [120, 60, 30];
const WIRE: Rgb = [60, 90, 150];
const FUR: Rgb = [214, 160, 108];
const FACET_EDGE: Rgb = [95, 62, 36];
/// Under the facets, showing through the wedges of bends.
const CREASE: Rgb = [150, 106, 66];
/// The cut faces a slice exposes (figure 3.7): a colour no other part of a figure uses.
const INNER: Rgb = [226, 40, 160];
const TEXEL_GRID: Rgb = [232, 230, 226];
const TILE: Rgb = [242, 240, 236];
/// Root, control near the middle, control near the tip, tip (figure 3.2).
const POINT_COLOURS: [Rgb; 4] = [[40, 150, 60], [40, 100, 210], [235, 130, 20], [205, 40, 40]];
/// One colour per shell layer, root first (figures 3.6, 3.7).
const BANDS: [Rgb; DIAGRAM_SHELLS as usize] = [
    [49, 104, 194],
    [38, 166, 154],
    [102, 180, 64],
    [222, 186, 30],
    [240, 128, 40],
    [208, 52, 70],
];

// ---------------------------------------------------------------------------------------------
// Drawing surface.

/// Text sizes in pixels ([`crate::font`]'s size: ascent − descent, not the em).
/// The figure's number and caption.
const TITLE_PX: f32 = 24.0;
/// Panel headings, point names, legends.
const LABEL_PX: f32 = 15.0;
/// The parameter line under the title, notes, height marks.
const NOTE_PX: f32 = 14.0;

/// A line of text, drawn over the figure at the end.
#[derive(Clone, Debug)]
struct Label {
    /// Left end of the text.
    x: f32,
    /// Top of its capitals (the baseline lies one capital height below).
    y: f32,
    text: String,
    px: f32,
    rgb: Rgb,
}

impl Label {
    /// The pixels the text covers visibly (coverage above 2 %).
    fn ink(&self) -> Vec<(u32, u32)> {
        let mut ink = Vec::new();
        self.rasterise(|x, y, coverage| {
            if coverage > 0.02 {
                ink.push((x, y));
            }
        });
        ink
    }

    /// Calls `plot(x, y, coverage)` for every pixel the text covers.
    fn rasterise(&self, plot: impl FnMut(u32, u32, f32)) {
        use ab_glyph::{Font as _, ScaleFont as _};
        let ascent = font::font()
            .as_scaled(ab_glyph::PxScale::from(self.px))
            .ascent();
        let line_top = self.y + font::cap_height(self.px) - ascent;
        font::rasterise(&self.text, self.x, line_top, self.px, plot);
    }
}

/// A tiny-skia pixmap plus the labels drawn over it at the end.
struct Canvas {
    pixmap: Pixmap,
    labels: Vec<Label>,
}

fn paint(rgb: Rgb, alpha: u8, anti_alias: bool) -> Paint<'static> {
    let mut p = Paint::default();
    p.set_color_rgba8(rgb[0], rgb[1], rgb[2], alpha);
    p.anti_alias = anti_alias;
    p
}

fn polygon(points: &[Vec2], builder: &mut PathBuilder) {
    for (k, p) in points.iter().enumerate() {
        if k == 0 {
            builder.move_to(p.x, p.y);
        } else {
            builder.line_to(p.x, p.y);
        }
    }
    builder.close();
}

impl Canvas {
    fn new() -> Self {
        let mut pixmap =
            Pixmap::new(DIAGRAM_WIDTH, DIAGRAM_HEIGHT).expect("the figure size is non-zero");
        pixmap.fill(Color::from_rgba8(
            BACKGROUND[0],
            BACKGROUND[1],
            BACKGROUND[2],
            255,
        ));
        Canvas {
            pixmap,
            labels: Vec::new(),
        }
    }

    /// Fills the union of `polygons` (one path, non-zero winding, so shared edges leave no seam).
    fn fill(&mut self, polygons: &[Vec<Vec2>], rgb: Rgb, alpha: u8, anti_alias: bool) {
        let mut builder = PathBuilder::new();
        for p in polygons.iter().filter(|p| p.len() >= 3) {
            polygon(p, &mut builder);
        }
        if let Some(path) = builder.finish() {
            self.pixmap.fill_path(
                &path,
                &paint(rgb, alpha, anti_alias),
                FillRule::Winding,
                Transform::identity(),
                None,
            );
        }
    }

    fn stroke(&mut self, points: &[Vec2], rgb: Rgb, width: f32, dashed: bool, closed: bool) {
        let mut builder = PathBuilder::new();
        for (k, p) in points.iter().enumerate() {
            if k == 0 {
                builder.move_to(p.x, p.y);
            } else {
                builder.line_to(p.x, p.y);
            }
        }
        if closed {
            builder.close();
        }
        if let Some(path) = builder.finish() {
            let stroke = Stroke {
                width,
                dash: if dashed {
                    StrokeDash::new(vec![6.0, 4.0], 0.0)
                } else {
                    None
                },
                ..Stroke::default()
            };
            self.pixmap.stroke_path(
                &path,
                &paint(rgb, 255, true),
                &stroke,
                Transform::identity(),
                None,
            );
        }
    }

    fn disc(&mut self, centre: Vec2, radius: f32, fill: Rgb, outline: Option<Rgb>) {
        if let Some(path) = PathBuilder::from_circle(centre.x, centre.y, radius) {
            self.pixmap.fill_path(
                &path,
                &paint(fill, 255, true),
                FillRule::Winding,
                Transform::identity(),
                None,
            );
            if let Some(rgb) = outline {
                let stroke = Stroke {
                    width: 1.5,
                    ..Stroke::default()
                };
                self.pixmap.stroke_path(
                    &path,
                    &paint(rgb, 255, true),
                    &stroke,
                    Transform::identity(),
                    None,
                );
            }
        }
    }

    /// An axis-aligned rectangle without anti-aliasing (texels).
    fn rect(&mut self, x: f32, y: f32, w: f32, h: f32, rgb: Rgb) {
        if let Some(r) = Rect::from_xywh(x, y, w, h) {
            self.pixmap
                .fill_rect(r, &paint(rgb, 255, false), Transform::identity(), None);
        }
    }

    /// A line of text `px` high, its left end at `x` and the top of its capitals at `y`;
    /// returns the x after it.
    fn text(&mut self, x: f32, y: f32, text: &str, px: f32, rgb: Rgb) -> f32 {
        if text.is_empty() {
            return x;
        }
        self.labels.push(Label {
            x,
            y,
            text: text.to_string(),
            px,
            rgb,
        });
        x + font::text_width(text, px)
    }

    /// Whether `label` lies inside the figure with its ink, and `pad` pixels around it, over
    /// background only and clear of every other label's ink.
    fn is_clear(&self, label: &Label, pad: i64) -> bool {
        let (w, h) = (self.pixmap.width(), self.pixmap.height());
        if label.x < 0.0 || label.x + font::text_width(&label.text, label.px) > w as f32 {
            return false;
        }
        let taken: std::collections::HashSet<(u32, u32)> =
            self.labels.iter().flat_map(Label::ink).collect();
        let background = Color::from_rgba8(BACKGROUND[0], BACKGROUND[1], BACKGROUND[2], 255)
            .premultiply()
            .to_color_u8();
        label.ink().into_iter().all(|(x, y)| {
            (-pad..=pad).all(|dy| {
                (-pad..=pad).all(|dx| {
                    let (nx, ny) = (i64::from(x) + dx, i64::from(y) + dy);
                    if nx < 0 || ny < 0 || nx >= i64::from(w) || ny >= i64::from(h) {
                        return false;
                    }
                    let (nx, ny) = (nx as u32, ny as u32);
                    self.pixmap.pixel(nx, ny) == Some(background) && !taken.contains(&(nx, ny))
                })
            })
        })
    }

    /// [`Canvas::text`] at the first of `candidates` (top-left corners as for `text`) where its
    /// ink is two pixels clear of the drawing and of other labels; at the first if none is.
    fn text_clear(&mut self, candidates: &[Vec2], text: &str, px: f32, rgb: Rgb) {
        let label = |at: Vec2| Label {
            x: at.x,
            y: at.y,
            text: text.to_string(),
            px,
            rgb,
        };
        let at = candidates
            .iter()
            .copied()
            .find(|&c| self.is_clear(&label(c), 2))
            .or(candidates.first().copied())
            .unwrap_or(Vec2::ZERO);
        self.text(at.x, at.y, text, px, rgb);
    }

    /// [`Canvas::text`] ending at `right`.
    fn text_right(&mut self, right: f32, y: f32, text: &str, px: f32, rgb: Rgb) {
        self.text(right - font::text_width(text, px), y, text, px, rgb);
    }

    /// [`Canvas::text`] centred on `centre`.
    fn text_centred(&mut self, centre: f32, y: f32, text: &str, px: f32, rgb: Rgb) {
        self.text(centre - 0.5 * font::text_width(text, px), y, text, px, rgb);
    }

    /// A colour swatch as high as the label's capitals, and the label; returns the x after the
    /// label and a gap.
    fn swatch(&mut self, x: f32, y: f32, rgb: Rgb, label: &str) -> f32 {
        let h = libm::roundf(font::cap_height(LABEL_PX)) + 1.0;
        self.rect(x, y - 0.5, 14.0, h, rgb);
        self.stroke(
            &[
                Vec2::new(x, y - 0.5),
                Vec2::new(x + 14.0, y - 0.5),
                Vec2::new(x + 14.0, y - 0.5 + h),
                Vec2::new(x, y - 0.5 + h),
            ],
            MUTED,
            1.0,
            false,
            true,
        );
        self.text(x + 20.0, y, label, LABEL_PX, INK) + 20.0
    }

    /// The figure's number and caption, and one line of parameters under it.
    fn title(&mut self, figure: Figure, details: &str) {
        let title = format!("Figure {}   {}", figure.number(), figure.caption());
        self.text(20.0, 14.0, &title, TITLE_PX, INK);
        self.text(20.0, 42.0, details, NOTE_PX, MUTED);
    }

    /// The image without its labels, and the labels.
    fn drawing(self) -> (RgbaImage, Vec<Label>) {
        let (w, h) = (self.pixmap.width(), self.pixmap.height());
        // Every pixel is opaque (an opaque background under everything), so premultiplied and
        // straight RGBA are the same bytes.
        let image =
            RgbaImage::from_raw(w, h, self.pixmap.take()).expect("a pixmap is w·h RGBA pixels");
        (image, self.labels)
    }

    fn finish(self) -> RgbaImage {
        let (mut image, labels) = self.drawing();
        let (w, h) = image.dimensions();
        for label in &labels {
            label.rasterise(|x, y, coverage| {
                if x < w && y < h {
                    let p = image.get_pixel_mut(x, y);
                    for c in 0..3 {
                        let (under, over) = (f32::from(p[c]), f32::from(label.rgb[c]));
                        p[c] = (under + (over - under) * coverage)
                            .round()
                            .clamp(0.0, 255.0) as u8;
                    }
                }
            });
        }
        image
    }
}

/// A panel of the figure: a screen rectangle with a heading above its top edge.
#[derive(Clone, Copy, Debug)]
struct Panel {
    x: f32,
    y: f32,
    w: f32,
    h: f32,
}

/// `count` panels side by side under the title, `gap` pixels apart, `bottom` pixels above the
/// figure's lower edge.
fn panels(count: usize, bottom: f32) -> Vec<Panel> {
    let (left, top, gap) = (20.0, 84.0, 20.0);
    let n = count.max(1) as f32;
    let w = (DIAGRAM_WIDTH as f32 - 2.0 * left - gap * (n - 1.0)) / n;
    let h = DIAGRAM_HEIGHT as f32 - top - bottom;
    (0..count)
        .map(|k| Panel {
            x: left + k as f32 * (w + gap),
            y: top,
            w,
            h,
        })
        .collect()
}

impl Panel {
    fn heading(&self, canvas: &mut Canvas, label: &str) {
        canvas.text(self.x, self.y - 18.0, label, LABEL_PX, INK);
    }
}

// ---------------------------------------------------------------------------------------------
// Projection.

/// An orthographic view along `+y` tilted down by `elevation`, mapped to pixels by a uniform
/// `scale` and the pixel position `origin` of the world point `(0, ·, 0)` seen there.
#[derive(Clone, Copy, Debug)]
struct View {
    elevation: f32,
    scale: f32,
    origin: Vec2,
}

impl View {
    fn new(elevation_deg: f32) -> Self {
        View {
            elevation: elevation_deg.to_radians(),
            scale: 1.0,
            origin: Vec2::ZERO,
        }
    }

    /// Screen-up direction in the world.
    fn up(&self) -> Vec3 {
        Vec3::new(0.0, libm::sinf(self.elevation), libm::cosf(self.elevation))
    }

    /// Unit vector from the scene towards the viewer.
    fn toward_viewer(&self) -> Vec3 {
        Vec3::new(0.0, -libm::cosf(self.elevation), libm::sinf(self.elevation))
    }

    /// The view-plane coordinates of `p` (world units, `y` up).
    fn plane(&self, p: Vec3) -> Vec2 {
        Vec2::new(p.x, p.dot(self.up()))
    }

    fn px(&self, p: Vec3) -> Vec2 {
        let q = self.plane(p);
        Vec2::new(
            self.origin.x + q.x * self.scale,
            self.origin.y - q.y * self.scale,
        )
    }

    /// Distance from the viewer (larger is farther), for painting back to front.
    fn depth(&self, p: Vec3) -> f32 {
        -p.dot(self.toward_viewer())
    }

    /// The scale that fits view-plane `bounds` (min, max) into `panel` with `margin` pixels
    /// around, capped at `max_scale`.
    fn fit_scale(bounds: (Vec2, Vec2), panel: Panel, margin: f32) -> f32 {
        let size = (bounds.1 - bounds.0).max(Vec2::splat(1e-6));
        let sx = (panel.w - 2.0 * margin) / size.x;
        let sy = (panel.h - 2.0 * margin) / size.y;
        sx.min(sy).max(1e-3)
    }

    /// This view at `scale`, with view-plane `bounds` centred in `panel`.
    fn placed(mut self, scale: f32, bounds: (Vec2, Vec2), panel: Panel) -> Self {
        let centre = (bounds.0 + bounds.1) * 0.5;
        self.scale = scale;
        self.origin = Vec2::new(
            panel.x + panel.w * 0.5 - centre.x * scale,
            panel.y + panel.h * 0.5 + centre.y * scale,
        );
        self
    }
}

fn bounds(points: impl IntoIterator<Item = Vec2>) -> (Vec2, Vec2) {
    points.into_iter().fold(
        (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    )
}

// ---------------------------------------------------------------------------------------------
// Geometry: the generator's strand and the baker's cones.

fn check_resolution(name: &'static str, value: u32, min: u32) -> Result<u32, FurError> {
    if value < min || value > MAX_DIAGRAM_RESOLUTION {
        return Err(FurError::InvalidParameter {
            name,
            reason: format!("{value} is outside {min}..={MAX_DIAGRAM_RESOLUTION} for a diagram"),
        });
    }
    Ok(value)
}

/// The parameters every figure starts from (see [`Figure`]), with the options' resolutions.
fn base_params(options: &DiagramOptions, strand_resolution: u32) -> Result<FurParams, FurError> {
    let strand_resolution = check_resolution(
        "strand_resolution",
        options.strand_resolution.unwrap_or(strand_resolution),
        1,
    )?;
    let circle_resolution = check_resolution(
        "circle_resolution",
        options.circle_resolution.unwrap_or(10),
        3,
    )?;
    Ok(FurParams {
        number_of_strands: 1,
        strand_resolution,
        circle_resolution,
        number_of_shells: DIAGRAM_SHELLS,
        texture_resolution: 64,
        supersample: 1,
        min_height: 1.0,
        max_height: 1.0,
        slope_deg: 30.0,
        curl: 0.1,
        jitter: 0.1,
        base_thickness: 0.06,
        tip_thickness: 0.02,
        thickness_jitter: 0.0,
        colour_variation: 0.0,
        gaussian_sigma: 1000.0,
        ..FurParams::default()
    })
}

/// Strand 0 of the generator for `params` and `seed`, leaning along `+x` with its root at
/// [`ROOT`].
fn figure_strand(params: &FurParams, seed: u32) -> Result<Strand, FurError> {
    let strand = generate_strands(params, seed)?
        .into_iter()
        .next()
        .ok_or_else(|| FurError::InvalidParameter {
            name: "number_of_strands",
            reason: "a diagram needs one strand".into(),
        })?;
    let (c, s) = (strand.lean.x, strand.lean.y);
    let turn = |p: Vec3| {
        let v = p - strand.root;
        ROOT + Vec3::new(v.x * c + v.y * s, -v.x * s + v.y * c, v.z)
    };
    Ok(Strand {
        root: ROOT,
        control: strand.control.map(turn),
        lean: Vec2::X,
        ..strand
    })
}

/// The strand's cone chain, exactly as the baker builds it.
fn cones(strand: &Strand, params: &FurParams) -> Vec<ConeSegment> {
    let (mut chains, _) = cones_of(std::slice::from_ref(strand), params.strand_resolution);
    chains.pop().unwrap_or_default()
}

/// The corner of the ring around `centre` at facet boundary `j` of `c` (angle `j·2π/C` from
/// `e1` towards `e2`, the convention of the cone module).
fn ring_point(seg: &ConeSegment, centre: Vec3, radius: f32, j: u32, c: u32) -> Vec3 {
    let angle = j as f32 * core::f32::consts::TAU / c.max(1) as f32;
    centre + (seg.e1 * libm::cosf(angle) + seg.e2 * libm::sinf(angle)) * radius
}

/// A flat polygon of a cone chain: a facet or a cap, with its outward normal and fill.
#[derive(Clone, Debug)]
struct Face {
    corners: Vec<Vec3>,
    normal: Vec3,
    rgb: Rgb,
    /// Whether it is lit (facets) or flat (cut faces).
    lit: bool,
}

/// The `c` facets of `seg`, coloured `rgb`.
fn facets(seg: &ConeSegment, c: u32, rgb: Rgb) -> Vec<Face> {
    let d = seg.p1 - seg.p0;
    (0..c)
        .map(|j| {
            let mid = (j as f32 + 0.5) * core::f32::consts::TAU / c.max(1) as f32;
            let radial = seg.e1 * libm::cosf(mid) + seg.e2 * libm::sinf(mid);
            // Perpendicular to the slanted side line d + (r1 − r0)·radial, in the plane of the
            // axis and the radial direction.
            let normal = (radial * d.length() - seg.axis * (seg.r1 - seg.r0)).normalize_or(radial);
            Face {
                corners: vec![
                    ring_point(seg, seg.p0, seg.r0, j, c),
                    ring_point(seg, seg.p0, seg.r0, j + 1, c),
                    ring_point(seg, seg.p1, seg.r1, j + 1, c),
                    ring_point(seg, seg.p1, seg.r1, j, c),
                ],
                normal,
                rgb,
                lit: true,
            }
        })
        .collect()
}

/// The cap of `seg` at its top end (`p1`), perpendicular to its axis.
fn top_cap(seg: &ConeSegment, c: u32, rgb: Rgb, lit: bool) -> Face {
    Face {
        corners: (0..c)
            .map(|j| ring_point(seg, seg.p1, seg.r1, j, c))
            .collect(),
        normal: seg.axis,
        rgb,
        lit,
    }
}

/// The parts of the cone chain inside heights `[z0, z1]`, clipped as the baker clips them.
fn slab(cones: &[ConeSegment], z0: f32, z1: f32, last: bool) -> Vec<ConeSegment> {
    cones
        .iter()
        .filter(|c| c.is_finite())
        .filter_map(|c| {
            let (lo, hi) = clip_to_slab(c, z0, z1, last)?;
            let d = c.p1 - c.p0;
            let dr = c.r1 - c.r0;
            Some(ConeSegment::new(
                c.p0 + d * lo,
                c.p0 + d * hi,
                c.r0 + dr * lo,
                c.r0 + dr * hi,
            ))
        })
        .collect()
}

/// The greatest height the strand's cone chain reaches: the baker's `H`.
fn top_height(strand: &Strand, params: &FurParams) -> f32 {
    let (_, top) = cones_of(std::slice::from_ref(strand), params.strand_resolution);
    if top > 0.0 { top } else { params.max_height }
}

/// Direction the figures' light comes from: front, left and above.
fn light() -> Vec3 {
    Vec3::new(-0.45, -0.65, 0.62).normalize()
}

fn shade(rgb: Rgb, normal: Vec3) -> Rgb {
    let k = 0.5 + 0.5 * normal.dot(light()).max(0.0);
    rgb.map(|c| (c as f32 * k).round().clamp(0.0, 255.0) as u8)
}

/// Fills the outline of a cone chain in a darker fur colour, under its faces: where a bend opens
/// a wedge between two truncated cones, the wedge reads as a crease instead of a gap.
fn underlay(canvas: &mut Canvas, view: &View, chain: &[ConeSegment], c: u32) {
    canvas.fill(&silhouette(view, chain, c), CREASE, 255, true);
}

/// Paints `faces` back to front, skipping those facing away; `edges` outlines each.
fn paint_faces(canvas: &mut Canvas, view: &View, faces: &[Face], edges: Option<(Rgb, f32)>) {
    let toward = view.toward_viewer();
    let mut visible: Vec<(f32, &Face)> = faces
        .iter()
        .filter(|f| f.normal.dot(toward) > 0.0)
        .map(|f| {
            let centre = f.corners.iter().copied().sum::<Vec3>() / f.corners.len().max(1) as f32;
            (view.depth(centre), f)
        })
        .collect();
    visible.sort_by(|a, b| b.0.total_cmp(&a.0));
    for (_, face) in visible {
        let points: Vec<Vec2> = face.corners.iter().map(|&p| view.px(p)).collect();
        let rgb = if face.lit {
            shade(face.rgb, face.normal)
        } else {
            face.rgb
        };
        canvas.fill(std::slice::from_ref(&points), rgb, 255, true);
        if let Some((edge, width)) = edges {
            canvas.stroke(&points, edge, width, false, true);
        }
    }
}

/// `points` turned counter-clockwise on screen (so that non-zero filling unites them).
fn counter_clockwise(mut points: Vec<Vec2>) -> Vec<Vec2> {
    let area: f32 = (0..points.len())
        .map(|k| points[k].perp_dot(points[(k + 1) % points.len()]))
        .sum();
    if area < 0.0 {
        points.reverse();
    }
    points
}

/// The convex hull of `points` (Andrew's monotone chain), counter-clockwise on screen.
fn convex_hull(mut points: Vec<Vec2>) -> Vec<Vec2> {
    points.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    if points.len() < 3 {
        return points;
    }
    let mut hull: Vec<Vec2> = Vec::with_capacity(2 * points.len());
    for pass in 0..2 {
        let start = hull.len();
        let ordered: Vec<Vec2> = if pass == 0 {
            points.clone()
        } else {
            points.iter().rev().copied().collect()
        };
        for p in ordered {
            while hull.len() >= start + 2
                && (hull[hull.len() - 1] - hull[hull.len() - 2]).perp_dot(p - hull[hull.len() - 2])
                    <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    counter_clockwise(hull)
}

/// The screen outline of a cone chain: every facet, and the hull of the two rings at each
/// joint (where the truncated cones of a bend leave a wedge open), all counter-clockwise.
fn silhouette(view: &View, segments: &[ConeSegment], c: u32) -> Vec<Vec<Vec2>> {
    let mut polygons: Vec<Vec<Vec2>> = segments
        .iter()
        .flat_map(|s| facets(s, c, FUR))
        .map(|f| counter_clockwise(f.corners.iter().map(|&p| view.px(p)).collect()))
        .collect();
    for pair in segments.windows(2) {
        let (a, b) = (&pair[0], &pair[1]);
        let rings = (0..c).flat_map(|j| {
            [
                view.px(ring_point(a, a.p1, a.r1, j, c)),
                view.px(ring_point(b, b.p0, b.r0, j, c)),
            ]
        });
        polygons.push(convex_hull(rings.collect()));
    }
    polygons
}

/// Every corner of the cone chain (for fitting a view).
fn chain_points(cones: &[ConeSegment], c: u32) -> Vec<Vec3> {
    cones
        .iter()
        .flat_map(|s| {
            (0..c).flat_map(move |j| {
                [
                    ring_point(s, s.p0, s.r0, j, c),
                    ring_point(s, s.p1, s.r1, j, c),
                ]
            })
        })
        .collect()
}

fn curve_points(strand: &Strand, n: u32) -> Vec<Vec3> {
    (0..=n)
        .map(|k| bezier_point(strand, k as f32 / n as f32))
        .collect()
}

// ---------------------------------------------------------------------------------------------
// The figures.

/// Screen-space facts a figure's tests check (where the inner colour may appear, which pixel is
/// the root), kept beside the canvas.
#[derive(Default)]
struct Marks {
    /// Screen polygons that the inner colour may fill (figure 3.7).
    inner_regions: Vec<Vec<Vec2>>,
    /// Screen position of the root, per panel.
    roots: Vec<Vec2>,
}

struct Drawn {
    canvas: Canvas,
    #[cfg_attr(not(test), allow(dead_code))]
    marks: Marks,
}

impl Drawn {
    fn finish(self) -> RgbaImage {
        self.canvas.finish()
    }
}

fn render(figure: Figure, options: &DiagramOptions) -> Result<Drawn, FurError> {
    match figure {
        Figure::Strand => strand_figure(options),
        Figure::Cones => cones_figure(options),
        Figure::Thickness => thickness_figure(options),
        Figure::Slope => slope_figure(options),
        Figure::Shells => shells_figure(options),
        Figure::InnerOuter => inner_outer_figure(options),
    }
}

/// 3.2: the Bézier strand, side view.
fn strand_figure(options: &DiagramOptions) -> Result<Drawn, FurError> {
    let params = base_params(options, 20)?;
    let strand = figure_strand(&params, options.seed)?;
    let mut canvas = Canvas::new();
    let mut marks = Marks::default();
    canvas.title(
        Figure::Strand,
        &format!(
            "Seed {}: strand 0 of the generator. Height 1, slope 30°, curl 0.1, jitter 0.1. Side view.",
            options.seed
        ),
    );
    let panel = Panel {
        x: 20.0,
        y: 70.0,
        w: 560.0,
        h: 450.0,
    };
    let view = View::new(0.0);
    let curve = curve_points(&strand, 200);
    let b = bounds(
        curve
            .iter()
            .chain(strand.control.iter())
            .map(|&p| view.plane(p)),
    );
    let b = (b.0 - Vec2::new(0.15, 0.05), b.1 + Vec2::new(0.15, 0.05));
    let view = view.placed(View::fit_scale(b, panel, 10.0), b, panel);
    // Ground.
    canvas.stroke(
        &[
            view.px(Vec3::new(b.0.x, 0.0, 0.0)),
            view.px(Vec3::new(b.1.x, 0.0, 0.0)),
        ],
        GROUND,
        2.0,
        false,
        false,
    );
    // Control polygon, curve, samples, control points.
    let control: Vec<Vec2> = strand.control.iter().map(|&p| view.px(p)).collect();
    canvas.stroke(&control, GUIDE, 1.5, true, false);
    let line: Vec<Vec2> = curve.iter().map(|&p| view.px(p)).collect();
    canvas.stroke(&line, CURVE, 4.0, false, false);
    for p in curve_points(&strand, params.strand_resolution) {
        canvas.disc(view.px(p), 3.0, BACKGROUND, Some(CURVE));
    }
    let names = [
        "P0 root",
        "P1 control near the middle",
        "P2 control near the tip",
        "P3 tip",
    ];
    for (&p, rgb) in control.iter().zip(POINT_COLOURS) {
        canvas.disc(p, 7.0, rgb, Some(INK));
    }
    // Each name beside its point, on the first side where it covers nothing drawn.
    let cap = font::cap_height(LABEL_PX);
    for (&p, name) in control.iter().zip(names) {
        let w = font::text_width(name, LABEL_PX);
        let candidates = [
            Vec2::new(p.x + 13.0, p.y - 0.5 * cap),
            Vec2::new(p.x - 13.0 - w, p.y - 0.5 * cap),
            Vec2::new(p.x + 10.0, p.y + 12.0),
            Vec2::new(p.x - 10.0 - w, p.y + 12.0),
            Vec2::new(p.x + 10.0, p.y - 12.0 - cap),
            Vec2::new(p.x - 10.0 - w, p.y - 12.0 - cap),
        ];
        canvas.text_clear(&candidates, name, LABEL_PX, INK);
    }
    marks.roots.push(view.px(strand.root));

    // Legend.
    let (x, mut y) = (590.0, 110.0);
    let lines = [
        "A cubic Bézier curve from root to tip:".to_string(),
        "P1 at half the height, a quarter of the run;".to_string(),
        "P2 at 85 % of the height, three quarters of".to_string(),
        "the run plus the curl; each point jittered.".to_string(),
        String::new(),
        format!(
            "Small dots: the {} samples (strand_resolution)",
            params.strand_resolution
        ),
        "that the cones and the baker use.".to_string(),
    ];
    for l in &lines {
        canvas.text(x, y, l, LABEL_PX, INK);
        y += 20.0;
    }
    y += 16.0;
    for (rgb, name) in POINT_COLOURS.iter().zip(names) {
        canvas.swatch(x, y, *rgb, name);
        y += 22.0;
    }
    let mid = y + 0.5 * cap;
    canvas.stroke(
        &[Vec2::new(x, mid), Vec2::new(x + 14.0, mid)],
        CURVE,
        4.0,
        false,
        false,
    );
    canvas.text(x + 20.0, y, "the curve", LABEL_PX, INK);
    y += 22.0;
    let mid = y + 0.5 * cap;
    canvas.stroke(
        &[Vec2::new(x, mid), Vec2::new(x + 14.0, mid)],
        GUIDE,
        1.5,
        true,
        false,
    );
    canvas.text(x + 20.0, y, "control polygon", LABEL_PX, INK);
    Ok(Drawn { canvas, marks })
}

/// The wireframe of a cone chain: rings at every segment end and the `c` side lines.
fn wireframe(canvas: &mut Canvas, view: &View, cones: &[ConeSegment], c: u32) {
    for seg in cones {
        for (centre, radius) in [(seg.p0, seg.r0), (seg.p1, seg.r1)] {
            let ring: Vec<Vec2> = (0..c)
                .map(|j| view.px(ring_point(seg, centre, radius, j, c)))
                .collect();
            canvas.stroke(&ring, WIRE, 1.0, false, true);
        }
        for j in 0..c {
            canvas.stroke(
                &[
                    view.px(ring_point(seg, seg.p0, seg.r0, j, c)),
                    view.px(ring_point(seg, seg.p1, seg.r1, j, c)),
                ],
                WIRE,
                0.8,
                false,
                false,
            );
        }
    }
}

/// The facets of a cone chain and the top cap of every segment: the tip's, and those inside the
/// chain, which show only through the wedges a bend opens between two truncated cones.
fn solid_faces(cones: &[ConeSegment], c: u32) -> Vec<Face> {
    cones
        .iter()
        .flat_map(|s| {
            let mut faces = facets(s, c, FUR);
            faces.push(top_cap(s, c, FUR, true));
            faces
        })
        .collect()
}

/// 3.3: the cone chain around the curve, wireframe and shaded.
fn cones_figure(options: &DiagramOptions) -> Result<Drawn, FurError> {
    let params = FurParams {
        base_thickness: 0.08,
        tip_thickness: 0.03,
        ..base_params(options, 8)?
    };
    let c = params.circle_resolution;
    let strand = figure_strand(&params, options.seed)?;
    let chain = cones(&strand, &params);
    let mut canvas = Canvas::new();
    let mut marks = Marks::default();
    canvas.title(
        Figure::Cones,
        &format!(
            "Seed {}. {} segments along (strand_resolution), {} facets around (circle_resolution); radius 0.08 at the root to 0.03 at the tip.",
            options.seed, params.strand_resolution, c
        ),
    );
    let ps = panels(2, 40.0);
    let view = View::new(20.0);
    let b = bounds(chain_points(&chain, c).into_iter().map(|p| view.plane(p)));
    let scale = View::fit_scale(b, ps[0], 20.0);
    let left = view.placed(scale, b, ps[0]);
    ps[0].heading(
        &mut canvas,
        "(a) The Bézier axis inside its cones (wireframe)",
    );
    wireframe(&mut canvas, &left, &chain, c);
    let line: Vec<Vec2> = curve_points(&strand, 200)
        .iter()
        .map(|&p| left.px(p))
        .collect();
    canvas.stroke(&line, CURVE, 3.0, false, false);
    for p in curve_points(&strand, params.strand_resolution) {
        canvas.disc(left.px(p), 3.0, BACKGROUND, Some(CURVE));
    }
    let right = view.placed(scale, b, ps[1]);
    ps[1].heading(
        &mut canvas,
        "(b) The same cones as flat facets (what the baker slices)",
    );
    underlay(&mut canvas, &right, &chain, c);
    paint_faces(
        &mut canvas,
        &right,
        &solid_faces(&chain, c),
        Some((FACET_EDGE, 0.7)),
    );
    marks.roots = vec![left.px(strand.root), right.px(strand.root)];
    let y = DIAGRAM_HEIGHT as f32 - 28.0;
    let x = canvas.swatch(
        20.0,
        y,
        WIRE,
        "rings at the segment ends, side lines at facet edges",
    );
    canvas.swatch(x, y, CURVE, "the Bézier curve and its samples");
    Ok(Drawn { canvas, marks })
}

/// 3.4: thick and thin strands from the same draws.
fn thickness_figure(options: &DiagramOptions) -> Result<Drawn, FurError> {
    let base = base_params(options, 20)?;
    let c = base.circle_resolution;
    let variants = [
        (
            0.08f32,
            0.03f32,
            "(a) Thick: radius 0.08 at the root, 0.03 at the tip",
        ),
        (
            0.025,
            0.008,
            "(b) Thin: radius 0.025 at the root, 0.008 at the tip",
        ),
    ];
    let mut chains = Vec::new();
    let mut strands = Vec::new();
    for (r0, r1, _) in variants {
        let params = FurParams {
            base_thickness: r0,
            tip_thickness: r1,
            ..base.clone()
        };
        let strand = figure_strand(&params, options.seed)?;
        chains.push(cones(&strand, &params));
        strands.push(strand);
    }
    let mut canvas = Canvas::new();
    let mut marks = Marks::default();
    canvas.title(
        Figure::Thickness,
        &format!(
            "Seed {}: the same generator draws with two thicknesses, at one scale. {} segments, {} facets.",
            options.seed, base.strand_resolution, c
        ),
    );
    let ps = panels(2, 30.0);
    let view = View::new(20.0);
    let b = bounds(
        chains
            .iter()
            .flat_map(|ch| chain_points(ch, c))
            .map(|p| view.plane(p)),
    );
    let scale = View::fit_scale(b, ps[0], 20.0);
    for (k, (chain, panel)) in chains.iter().zip(&ps).enumerate() {
        let v = view.placed(scale, b, *panel);
        panel.heading(&mut canvas, variants[k].2);
        underlay(&mut canvas, &v, chain, c);
        paint_faces(&mut canvas, &v, &solid_faces(chain, c), None);
        marks.roots.push(v.px(strands[k].root));
    }
    Ok(Drawn { canvas, marks })
}

/// 3.5: normal and higher slope, side view, with the run marked.
fn slope_figure(options: &DiagramOptions) -> Result<Drawn, FurError> {
    let base = FurParams {
        base_thickness: 0.04,
        tip_thickness: 0.012,
        ..base_params(options, 20)?
    };
    let c = base.circle_resolution;
    let slopes = [
        (FurParams::default().slope_deg, "(a) Normal slope"),
        (50.0f32, "(b) Higher slope"),
    ];
    let mut strands = Vec::new();
    let mut chains = Vec::new();
    for (slope, _) in slopes {
        let params = FurParams {
            slope_deg: slope,
            ..base.clone()
        };
        let strand = figure_strand(&params, options.seed)?;
        chains.push(cones(&strand, &params));
        strands.push(strand);
    }
    let mut canvas = Canvas::new();
    let mut marks = Marks::default();
    canvas.title(
        Figure::Slope,
        &format!(
            "Seed {}: the same generator draws at slope {}° and {}° (each jittered by 10 %). Side view, one scale.",
            options.seed, slopes[0].0, slopes[1].0
        ),
    );
    let ps = panels(2, 30.0);
    let view = View::new(0.0);
    let b = bounds(
        chains
            .iter()
            .flat_map(|ch| chain_points(ch, c))
            .map(|p| view.plane(p)),
    );
    let b = (b.0 - Vec2::new(0.05, 0.12), b.1 + Vec2::new(0.05, 0.0));
    let scale = View::fit_scale(b, ps[0], 16.0);
    for (k, panel) in ps.iter().enumerate() {
        let v = view.placed(scale, b, *panel);
        let strand = &strands[k];
        let tip = strand.control[3];
        let run = tip.x - strand.root.x;
        panel.heading(
            &mut canvas,
            &format!("{} {}°: run {:.2}", slopes[k].1, slopes[k].0, run),
        );
        canvas.stroke(
            &[
                v.px(Vec3::new(b.0.x, 0.0, 0.0)),
                v.px(Vec3::new(b.1.x, 0.0, 0.0)),
            ],
            GROUND,
            2.0,
            false,
            false,
        );
        // The vertical through the root, and the run from the root to below the tip.
        canvas.stroke(
            &[v.px(strand.root), v.px(strand.root + Vec3::Z * tip.z)],
            GUIDE,
            1.0,
            true,
            false,
        );
        canvas.stroke(
            &[v.px(tip), v.px(Vec3::new(tip.x, 0.0, 0.0))],
            GUIDE,
            1.0,
            true,
            false,
        );
        underlay(&mut canvas, &v, &chains[k], c);
        paint_faces(&mut canvas, &v, &solid_faces(&chains[k], c), None);
        let line: Vec<Vec2> = curve_points(strand, 200).iter().map(|&p| v.px(p)).collect();
        canvas.stroke(&line, CURVE, 1.5, false, false);
        let y = v.px(strand.root).y + 0.06 * scale;
        let (x0, x1) = (v.px(strand.root).x, v.px(tip).x);
        canvas.stroke(
            &[Vec2::new(x0, y), Vec2::new(x1, y)],
            INK,
            1.5,
            false,
            false,
        );
        for x in [x0, x1] {
            canvas.stroke(
                &[Vec2::new(x, y - 5.0), Vec2::new(x, y + 5.0)],
                INK,
                1.5,
                false,
                false,
            );
        }
        canvas.text_centred((x0 + x1) * 0.5, y + 10.0, "run", LABEL_PX, INK);
        canvas.disc(v.px(strand.root), 5.0, POINT_COLOURS[0], Some(INK));
        canvas.disc(v.px(tip), 5.0, POINT_COLOURS[3], Some(INK));
        marks.roots.push(v.px(strand.root));
    }
    Ok(Drawn { canvas, marks })
}

/// Texels of a layer window shown as squares: texel `(x, y)` (row `y` = texture `v`) at
/// screen `left + (x − x0)·size`, rows flipped so that `+y` is up.
#[derive(Clone, Copy, Debug)]
struct TexelWindow {
    x0: i64,
    y0: i64,
    w: i64,
    h: i64,
    resolution: u32,
    size: f32,
    left: f32,
    top: f32,
}

impl TexelWindow {
    /// The smallest window holding every covered texel of `layers`, with `margin` texels
    /// around, scaled to whole pixels per texel and centred in `panel`.
    fn around(layers: &[&ShellLayer], resolution: u32, margin: i64, panel: Panel) -> Self {
        let (mut lo, mut hi) = ((i64::MAX, i64::MAX), (i64::MIN, i64::MIN));
        for layer in layers {
            for (i, t) in layer.colour.texels.iter().enumerate() {
                if t[3] > 0 {
                    let (x, y) = (
                        (i % resolution as usize) as i64,
                        (i / resolution as usize) as i64,
                    );
                    lo = (lo.0.min(x), lo.1.min(y));
                    hi = (hi.0.max(x), hi.1.max(y));
                }
            }
        }
        if lo.0 > hi.0 {
            lo = (0, 0);
            hi = (i64::from(resolution) - 1, i64::from(resolution) - 1);
        }
        let (x0, y0) = (lo.0 - margin, lo.1 - margin);
        let (w, h) = (hi.0 - lo.0 + 1 + 2 * margin, hi.1 - lo.1 + 1 + 2 * margin);
        let size = libm::floorf((panel.w / w as f32).min(panel.h / h as f32)).max(1.0);
        TexelWindow {
            x0,
            y0,
            w,
            h,
            resolution,
            size,
            left: panel.x + 0.5 * (panel.w - size * w as f32),
            top: panel.y + 0.5 * (panel.h - size * h as f32),
        }
    }

    /// Top-left screen corner of texel `(x, y)`.
    fn texel(&self, x: i64, y: i64) -> Vec2 {
        Vec2::new(
            self.left + (x - self.x0) as f32 * self.size,
            self.top + (self.y0 + self.h - 1 - y) as f32 * self.size,
        )
    }

    /// Screen position of the tile point `q`.
    fn point(&self, q: Vec2) -> Vec2 {
        let r = self.resolution as f32;
        Vec2::new(
            self.left + (q.x * r - self.x0 as f32) * self.size,
            self.top + ((self.y0 + self.h) as f32 - q.y * r) * self.size,
        )
    }

    /// The window's texels in the tile's colour with a faint grid.
    fn background(&self, canvas: &mut Canvas) {
        let (w, h) = (self.w as f32 * self.size, self.h as f32 * self.size);
        canvas.rect(self.left, self.top, w, h, TILE);
        if self.size >= 4.0 {
            for k in 0..=self.w {
                let x = self.left + k as f32 * self.size;
                canvas.rect(x, self.top, 1.0, h, TEXEL_GRID);
            }
            for k in 0..=self.h {
                let y = self.top + k as f32 * self.size;
                canvas.rect(self.left, y, w, 1.0, TEXEL_GRID);
            }
        }
    }

    /// Calls `f(x, y, index)` for every covered texel of `layer` inside the window.
    fn covered(&self, layer: &ShellLayer, mut f: impl FnMut(i64, i64, usize)) {
        let r = self.resolution as usize;
        for (i, t) in layer.colour.texels.iter().enumerate() {
            let (x, y) = ((i % r) as i64, (i / r) as i64);
            if t[3] > 0
                && (self.x0..self.x0 + self.w).contains(&x)
                && (self.y0..self.y0 + self.h).contains(&y)
            {
                f(x, y, i);
            }
        }
    }

    fn fill_texel(&self, canvas: &mut Canvas, x: i64, y: i64, rgb: Rgb) {
        let p = self.texel(x, y);
        canvas.rect(p.x, p.y, self.size, self.size, rgb);
    }
}

/// Figure 3.6's panels: the side view on the left, the top view and the flat shells on the
/// right, one above the other with the same columns.
fn shells_panels() -> [Panel; 3] {
    [
        Panel {
            x: 20.0,
            y: 84.0,
            w: 250.0,
            h: 400.0,
        },
        Panel {
            x: 300.0,
            y: 84.0,
            w: 640.0,
            h: 190.0,
        },
        Panel {
            x: 300.0,
            y: 306.0,
            w: 640.0,
            h: 178.0,
        },
    ]
}

/// 3.6: the strand sliced into shells, from the side and from the top.
fn shells_figure(options: &DiagramOptions) -> Result<Drawn, FurError> {
    let params = base_params(options, 20)?;
    let c = params.circle_resolution;
    let n = params.number_of_shells;
    let strand = figure_strand(&params, options.seed)?;
    let chain = cones(&strand, &params);
    let h = top_height(&strand, &params);
    let baked = bake_shells(&params, std::slice::from_ref(&strand))?;
    let mut canvas = Canvas::new();
    let mut marks = Marks::default();
    canvas.title(
        Figure::Shells,
        &format!(
            "Seed {}. N = {n} shells: layer i holds the strand between heights i·H/N and (i + 1)·H/N, H = {:.3}. Baked at {}×{} texels.",
            options.seed, h, params.texture_resolution, params.texture_resolution
        ),
    );
    let ps = shells_panels();

    // (A) Side view: each slice of the cone chain in its layer's colour, shell heights dashed.
    let view = View::new(0.0);
    let b = bounds(chain_points(&chain, c).into_iter().map(|p| view.plane(p)));
    let b = (b.0 - Vec2::new(0.04, 0.02), b.1 + Vec2::new(0.04, 0.02));
    let side = view.placed(View::fit_scale(b, ps[0], 14.0), b, ps[0]);
    ps[0].heading(&mut canvas, "(a) From the side: the strand sliced");
    for i in 0..n {
        let (z0, z1) = (h * i as f32 / n as f32, h * (i + 1) as f32 / n as f32);
        let parts = slab(&chain, z0, z1, i + 1 == n);
        let rgb = BANDS[i as usize % BANDS.len()];
        canvas.fill(&silhouette(&side, &parts, c), rgb, 255, true);
    }
    for i in 0..=n {
        let z = h * i as f32 / n as f32;
        let (a, e) = (
            Vec2::new(ps[0].x, side.px(Vec3::Z * z).y),
            Vec2::new(ps[0].x + ps[0].w, side.px(Vec3::Z * z).y),
        );
        canvas.stroke(&[a, e], GUIDE, 1.0, true, false);
        let label = match i {
            0 => "0".to_string(),
            1 => format!("H/{n}"),
            i if i == n => "H".to_string(),
            i => format!("{i}·H/{n}"),
        };
        canvas.text_right(
            ps[0].x + ps[0].w,
            a.y - 4.0 - font::cap_height(NOTE_PX),
            &label,
            NOTE_PX,
            MUTED,
        );
    }
    marks.roots.push(side.px(strand.root));

    // (B) Top view of the baked layers, root first, each covered texel in its layer's colour.
    let layers: Vec<&ShellLayer> = baked.layers.iter().collect();
    let window = TexelWindow::around(&layers, params.texture_resolution, 2, ps[1]);
    ps[1].heading(&mut canvas, "(b) From the top: the baked layers");
    window.background(&mut canvas);
    for (i, layer) in baked.layers.iter().enumerate() {
        let rgb = BANDS[i % BANDS.len()];
        window.covered(layer, |x, y, _| window.fill_texel(&mut canvas, x, y, rgb));
    }
    marks.roots.push(window.point(strand.root.truncate()));

    // (C) Side view of the shells as drawn: each layer's texels flat at its shell's height.
    ps[2].heading(
        &mut canvas,
        "(c) From the side: each layer flat on its shell",
    );
    let shell_gap = (ps[2].h - 30.0) / n as f32;
    let base_y = ps[2].y + ps[2].h - 10.0;
    // The columns of (B) above, so that each layer's extent lines up with its texels.
    let left = window.left;
    let mut shell_labels = Vec::new();
    for (i, layer) in baked.layers.iter().enumerate() {
        let y = base_y - i as f32 * shell_gap;
        let rgb = BANDS[i % BANDS.len()];
        canvas.stroke(
            &[
                Vec2::new(left, y),
                Vec2::new(left + window.w as f32 * window.size, y),
            ],
            GUIDE,
            1.0,
            false,
            false,
        );
        let mut columns = vec![false; window.w.max(0) as usize];
        window.covered(layer, |x, _, _| {
            if let Some(c) = columns.get_mut((x - window.x0) as usize) {
                *c = true;
            }
        });
        for (k, _) in columns.iter().enumerate().filter(|(_, c)| **c) {
            canvas.rect(
                left + k as f32 * window.size,
                y - 4.0,
                window.size,
                8.0,
                rgb,
            );
        }
        shell_labels.push((y, format!("shell {i}")));
    }
    // Above each shell's line, at the end its texels leave free.
    let cap = font::cap_height(NOTE_PX);
    let right = left + window.w as f32 * window.size;
    for (y, label) in shell_labels {
        let w = font::text_width(&label, NOTE_PX);
        let top = y - 7.0 - cap;
        canvas.text_clear(
            &[Vec2::new(right - w, top), Vec2::new(left, top)],
            &label,
            NOTE_PX,
            MUTED,
        );
    }
    let mut x = 20.0;
    let y = DIAGRAM_HEIGHT as f32 - 28.0;
    for (i, rgb) in BANDS.iter().enumerate().take(n as usize) {
        x = canvas.swatch(x, y, *rgb, &format!("layer {i}"));
    }
    canvas.text(
        x,
        y,
        "(c): the gaps a side view shows are why fins exist",
        LABEL_PX,
        MUTED,
    );
    Ok(Drawn { canvas, marks })
}

/// The axis point and radius where the cone chain crosses height `z` (first crossing).
fn cross_section(cones: &[ConeSegment], z: f32) -> Option<(Vec3, f32)> {
    cones.iter().find_map(|s| {
        let (za, zb) = (s.p0.z, s.p1.z);
        if za == zb || z < za.min(zb) || z > za.max(zb) {
            return None;
        }
        let t = (z - za) / (zb - za);
        Some((s.p0.lerp(s.p1, t), s.r0 + (s.r1 - s.r0) * t))
    })
}

/// The layer figure 3.7 looks at from the top (0-based: the third).
const INNER_LAYER: u32 = 2;

/// The top of figure 3.7's legend: below it, the inner colour appears only in its swatch.
const LEGEND_3_7_TOP: f32 = DIAGRAM_HEIGHT as f32 - 40.0;

/// 3.7: inner (cut) and outer parts of the slices, and the tangents the baker stores.
fn inner_outer_figure(options: &DiagramOptions) -> Result<Drawn, FurError> {
    let params = FurParams {
        base_thickness: 0.12,
        tip_thickness: 0.01,
        texture_resolution: 96,
        ..base_params(options, 20)?
    };
    let c = params.circle_resolution;
    let n = params.number_of_shells;
    let strand = figure_strand(&params, options.seed)?;
    let chain = cones(&strand, &params);
    let h = top_height(&strand, &params);
    let baked = bake_shells(&params, std::slice::from_ref(&strand))?;
    let mut canvas = Canvas::new();
    let mut marks = Marks::default();
    canvas.title(
        Figure::InnerOuter,
        &format!(
            "Seed {}. Radius 0.12 to 0.01, {} shells, {} facets. Slicing exposes the inside; the baker gives it the outer facet’s tangent.",
            options.seed, n, c
        ),
    );
    let ps = panels(4, 40.0);

    // (A) Exploded oblique view: slice i lifted by i·gap, its top cut face in the inner colour.
    let view = View::new(28.0);
    let gap = 0.1 * h;
    let mut faces = Vec::new();
    let mut slices = Vec::new();
    for i in 0..n {
        let (z0, z1) = (h * i as f32 / n as f32, h * (i + 1) as f32 / n as f32);
        let lift = Vec3::Z * (gap * i as f32);
        let parts: Vec<ConeSegment> = slab(&chain, z0, z1, i + 1 == n)
            .into_iter()
            .map(|s| ConeSegment::new(s.p0 + lift, s.p1 + lift, s.r0, s.r1))
            .collect();
        let inside = parts.len().saturating_sub(1);
        faces.extend(solid_faces(&parts[..inside], c));
        faces.extend(parts.iter().skip(inside).flat_map(|s| facets(s, c, FUR)));
        if let Some(last) = parts.last() {
            // The top of the last slice is the strand's own tip, not a cut.
            let cut = i + 1 < n;
            faces.push(top_cap(last, c, if cut { INNER } else { FUR }, !cut));
        }
        slices.push(parts);
    }
    let lifted_all: Vec<ConeSegment> = slices.iter().flatten().copied().collect();
    let b = bounds(
        chain_points(&lifted_all, c)
            .into_iter()
            .map(|p| view.plane(p)),
    );
    let a_view = view.placed(View::fit_scale(b, ps[0], 10.0), b, ps[0]);
    ps[0].heading(&mut canvas, "(a) The slices, pulled apart");
    for slice in &slices {
        underlay(&mut canvas, &a_view, slice, c);
    }
    paint_faces(&mut canvas, &a_view, &faces, Some((FACET_EDGE, 0.5)));
    if let Some(cut) = slices.get(INNER_LAYER as usize).and_then(|s| s.last()) {
        let p = a_view.px(cut.p1);
        let label = format!("← layer {INNER_LAYER}");
        let (x, y) = (
            p.x + cut.r1 * a_view.scale + 10.0,
            p.y - 0.5 * font::cap_height(LABEL_PX),
        );
        let candidates: Vec<Vec2> = (0..8).map(|k| Vec2::new(x + 8.0 * k as f32, y)).collect();
        canvas.text_clear(&candidates, &label, LABEL_PX, INK);
    }
    for f in faces.iter().filter(|f| f.rgb == INNER) {
        marks
            .inner_regions
            .push(f.corners.iter().map(|&p| a_view.px(p)).collect());
    }
    marks.roots.push(a_view.px(strand.root));

    // (B)–(D) Top view of one layer: inner and outer texels, and the stored tangents.
    let z1 = h * (INNER_LAYER + 1) as f32 / n as f32;
    let (cut_centre, cut_radius) = cross_section(&chain, z1).unwrap_or((strand.root, 0.0));
    let layer =
        baked
            .layers
            .get(INNER_LAYER as usize)
            .ok_or_else(|| FurError::InvalidParameter {
                name: "number_of_shells",
                reason: "too few shells for the figure".into(),
            })?;
    let window = TexelWindow::around(&[layer], params.texture_resolution, 2, ps[1]);
    let inner = |x: i64, y: i64| {
        let r = params.texture_resolution as f32;
        let q = Vec2::new((x as f32 + 0.5) / r, (y as f32 + 0.5) / r);
        q.distance(cut_centre.truncate()) <= cut_radius
    };
    let circle: Vec<Vec2> = (0..64)
        .map(|k| {
            let a = k as f32 * core::f32::consts::TAU / 64.0;
            cut_centre.truncate() + Vec2::new(libm::cosf(a), libm::sinf(a)) * cut_radius
        })
        .collect();
    let mut mean = Vec3::ZERO;
    let mut count = 0.0f32;
    window.covered(layer, |_, _, i| {
        if let Some(t) = layer.tangent.texels.get(i) {
            mean += Vec3::new(t[0] as f32, t[1] as f32, t[2] as f32);
            count += 1.0;
        }
    });
    let mean = mean / count.max(1.0);
    let headings = [
        format!("(b) Layer {INNER_LAYER} from the top"),
        "(c) Its stored tangents".to_string(),
        "(d) The same, contrast ×4".to_string(),
    ];
    for (k, panel) in ps.iter().enumerate().skip(1) {
        let w = TexelWindow {
            left: panel.x + 0.5 * (panel.w - window.size * window.w as f32),
            ..window
        };
        panel.heading(&mut canvas, &headings[k - 1]);
        w.background(&mut canvas);
        let mut inner_cells = Vec::new();
        w.covered(layer, |x, y, i| {
            let stored = layer.tangent.texels.get(i).copied().unwrap_or_default();
            let rgb = match k {
                1 if inner(x, y) => INNER,
                1 => FUR,
                2 => [stored[0], stored[1], stored[2]],
                _ => [0, 1, 2].map(|ch| {
                    let v = mean[ch] + 4.0 * (stored[ch] as f32 - mean[ch]);
                    v.round().clamp(0.0, 255.0) as u8
                }),
            };
            w.fill_texel(&mut canvas, x, y, rgb);
            if k == 1 && inner(x, y) {
                inner_cells.push(w.texel(x, y));
            }
        });
        for p in inner_cells {
            let s = w.size;
            marks.inner_regions.push(vec![
                p,
                p + Vec2::new(s, 0.0),
                p + Vec2::new(s, s),
                p + Vec2::new(0.0, s),
            ]);
        }
        let outline: Vec<Vec2> = circle.iter().map(|&q| w.point(q)).collect();
        canvas.stroke(&outline, INK, 1.5, true, true);
    }
    let y = LEGEND_3_7_TOP + 2.0;
    let x = canvas.swatch(20.0, y, INNER, "inner: the cut face a slice exposes");
    let x = canvas.swatch(x, y, FUR, "outer surface");
    canvas.text(
        x,
        y,
        "dashed: the cut circle at the layer’s top height",
        LABEL_PX,
        MUTED,
    );
    canvas.text(
        20.0,
        y + 19.0,
        "(c), (d): inside the circle each texel carries the tangent of the outer facet at its angle (tangent map: RGB = t·0.5 + 0.5).",
        NOTE_PX,
        MUTED,
    );
    Ok(Drawn { canvas, marks })
}

#[cfg(test)]
mod tests {
    use super::super::cone::FacetTable;
    use super::super::image::tangent_to_rgb8;
    use super::*;

    fn draw(figure: Figure) -> RgbaImage {
        draw_diagram(figure, &DiagramOptions::new(1234)).expect("draws")
    }

    fn is(image: &RgbaImage, x: u32, y: u32, rgb: Rgb) -> bool {
        let p = image.get_pixel(x, y).0;
        [p[0], p[1], p[2]] == rgb
    }

    /// Pixels inside `rect` that are not the background.
    fn ink(image: &RgbaImage, x0: u32, x1: u32, y0: u32, y1: u32) -> usize {
        (y0..y1)
            .flat_map(|y| (x0..x1).map(move |x| (x, y)))
            .filter(|&(x, y)| !is(image, x, y, BACKGROUND))
            .count()
    }

    #[test]
    fn every_figure_is_deterministic_and_opaque() {
        for figure in Figure::ALL {
            let a = draw(figure);
            let b = draw(figure);
            assert_eq!((a.width(), a.height()), (DIAGRAM_WIDTH, DIAGRAM_HEIGHT));
            assert!(
                a.as_raw() == b.as_raw(),
                "figure {} differs",
                figure.number()
            );
            assert!(a.pixels().all(|p| p.0[3] == 255), "{}", figure.number());
            // Another seed gives another strand.
            let other = draw_diagram(figure, &DiagramOptions::new(99)).expect("draws");
            assert!(a.as_raw() != other.as_raw(), "{}", figure.number());
        }
    }

    /// Every label of `figure`: inside the figure, its ink (and a pixel around it) over the
    /// background only, and at least three pixels from every other label's ink.
    fn check_labels(figure: Figure, seed: u32) {
        let drawn = render(figure, &DiagramOptions::new(seed)).expect("draws");
        let (image, labels) = drawn.canvas.drawing();
        let (w, h) = image.dimensions();
        let mut owner: Vec<Option<usize>> = vec![None; (w * h) as usize];
        for (k, label) in labels.iter().enumerate() {
            let width = font::text_width(&label.text, label.px);
            assert!(
                label.x >= 0.0 && label.x + width <= w as f32 && label.y >= 0.0,
                "figure {} seed {seed}: {:?} leaves the figure",
                figure.number(),
                label.text
            );
            let ink = label.ink();
            assert!(!ink.is_empty(), "{:?} draws nothing", label.text);
            for (x, y) in ink {
                assert!(x < w && y < h, "{:?} leaves the figure", label.text);
                for (nx, ny) in [(0, 0), (-1, 0), (1, 0), (0, -1), (0, 1)]
                    .map(|(dx, dy)| (x as i64 + dx, y as i64 + dy))
                    .into_iter()
                    .filter(|&(nx, ny)| nx >= 0 && ny >= 0 && nx < w as i64 && ny < h as i64)
                {
                    let (nx, ny) = (nx as u32, ny as u32);
                    assert!(
                        is(&image, nx, ny, BACKGROUND),
                        "figure {} seed {seed}: {:?} covers the drawing at ({nx}, {ny})",
                        figure.number(),
                        label.text
                    );
                    let cell = &mut owner[(ny * w + nx) as usize];
                    if let Some(other) = *cell
                        && other != k
                    {
                        panic!(
                            "figure {} seed {seed}: {:?} touches {:?} at ({nx}, {ny})",
                            figure.number(),
                            label.text,
                            labels[other].text
                        );
                    }
                    *cell = Some(k);
                }
            }
        }
    }

    #[test]
    fn labels_are_clear_of_the_drawing_and_of_each_other() {
        // The documented seed, and two others: the labels that a strand could cover are placed
        // by measuring, not at fixed spots.
        for seed in [1234, 7, 99] {
            for figure in Figure::ALL {
                check_labels(figure, seed);
            }
        }
    }

    #[test]
    fn labels_read_in_mixed_case_with_symbols() {
        let drawn = render(Figure::Shells, &DiagramOptions::new(1234)).expect("draws");
        let texts: Vec<&str> = drawn
            .canvas
            .labels
            .iter()
            .map(|l| l.text.as_str())
            .collect();
        assert!(texts.iter().any(|t| t.contains("i·H/N")), "{texts:?}");
        assert!(texts.iter().any(|t| t.contains("64×64")), "{texts:?}");
        assert!(texts.contains(&"2·H/6"), "{texts:?}");
    }

    #[test]
    fn names_parse() {
        for figure in Figure::ALL {
            assert_eq!(Figure::parse(figure.number()), Some(figure));
            let dashed = figure.number().replace('.', "-");
            assert_eq!(Figure::parse(&format!("fig-{dashed}")), Some(figure));
            assert_eq!(Figure::parse(&dashed), Some(figure));
        }
        assert_eq!(Figure::parse("3.8"), None);
        assert_eq!(Figure::parse(""), None);
        assert_eq!(Figure::parse("fig"), None);
        assert_eq!(Figure::Thickness.file_name(), "fig-3-4.png");
    }

    #[test]
    fn resolutions_are_bounded() {
        let mut o = DiagramOptions::new(1);
        o.circle_resolution = Some(2);
        assert!(matches!(
            draw_diagram(Figure::Cones, &o),
            Err(FurError::InvalidParameter {
                name: "circle_resolution",
                ..
            })
        ));
        o.circle_resolution = Some(MAX_DIAGRAM_RESOLUTION + 1);
        assert!(draw_diagram(Figure::Cones, &o).is_err());
        o.circle_resolution = None;
        o.strand_resolution = Some(0);
        assert!(matches!(
            draw_diagram(Figure::Strand, &o),
            Err(FurError::InvalidParameter {
                name: "strand_resolution",
                ..
            })
        ));
        // Changing a resolution changes the cones drawn.
        o.strand_resolution = Some(3);
        let coarse = draw_diagram(Figure::Cones, &o).expect("draws");
        assert!(coarse.as_raw() != draw(Figure::Cones).as_raw());
    }

    #[test]
    fn figure_3_2_marks_all_four_points() {
        let image = draw(Figure::Strand);
        for rgb in POINT_COLOURS {
            let n = image
                .pixels()
                .filter(|p| [p.0[0], p.0[1], p.0[2]] == rgb)
                .count();
            // Each point's disc (radius 7) plus its legend swatch.
            assert!(n > 100, "{rgb:?}: {n}");
        }
    }

    #[test]
    fn figure_3_4_thick_covers_more_than_thin() {
        let drawn = render(Figure::Thickness, &DiagramOptions::new(1234)).expect("draws");
        let image = drawn.finish();
        let half = DIAGRAM_WIDTH / 2;
        // Below the headings, above the bottom margin.
        let thick = ink(&image, 0, half, 84, DIAGRAM_HEIGHT - 30);
        let thin = ink(&image, half, DIAGRAM_WIDTH, 84, DIAGRAM_HEIGHT - 30);
        assert!(thin > 500, "{thin}");
        assert!(
            thick as f64 > 2.0 * thin as f64,
            "thick {thick}, thin {thin}"
        );
    }

    /// The rightmost and leftmost non-background columns of a panel's strand area.
    fn extent(image: &RgbaImage, x0: u32, x1: u32) -> (u32, u32) {
        let cols: Vec<u32> = (x0..x1)
            .filter(|&x| {
                (84..DIAGRAM_HEIGHT - 30).any(|y| {
                    let p = image.get_pixel(x, y).0;
                    // Fur shades only: the strand, not guides, labels or the ground line.
                    i32::from(p[0]) > i32::from(p[2]) + 40 && p[0] > 60
                })
            })
            .collect();
        (
            cols.first().copied().unwrap_or(0),
            cols.last().copied().unwrap_or(0),
        )
    }

    #[test]
    fn figure_3_5_higher_slope_reaches_further() {
        let drawn = render(Figure::Slope, &DiagramOptions::new(1234)).expect("draws");
        let roots = drawn.marks.roots.clone();
        let image = drawn.finish();
        let half = DIAGRAM_WIDTH / 2;
        let (_, normal_right) = extent(&image, 0, half);
        let (_, high_right) = extent(&image, half, DIAGRAM_WIDTH);
        let normal_run = normal_right as f32 - roots[0].x;
        let high_run = high_right as f32 - roots[1].x;
        assert!(normal_run > 20.0, "{normal_run}");
        assert!(high_run > 1.5 * normal_run, "{high_run} vs {normal_run}");
    }

    #[test]
    fn figure_3_6_shows_one_band_per_shell() {
        let image = draw(Figure::Shells);
        let present = BANDS
            .iter()
            .filter(|rgb| {
                image
                    .pixels()
                    .filter(|p| [p.0[0], p.0[1], p.0[2]] == **rgb)
                    .count()
                    > 60
            })
            .count();
        assert_eq!(present, DIAGRAM_SHELLS as usize);
        // Each band appears in each of the three panels, not only in the legend.
        for panel in &shells_panels() {
            for rgb in BANDS {
                let found = (panel.y as u32..(panel.y + panel.h) as u32).any(|y| {
                    (panel.x as u32..(panel.x + panel.w) as u32).any(|x| is(&image, x, y, rgb))
                });
                assert!(found, "{rgb:?} missing from a panel at x = {}", panel.x);
            }
        }
    }

    fn inside(poly: &[Vec2], p: Vec2) -> bool {
        // Even-odd ray casting.
        let mut hit = false;
        for k in 0..poly.len() {
            let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
            if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
                hit = !hit;
            }
        }
        hit
    }

    #[test]
    fn figure_3_7_inner_colour_only_where_slicing_exposes_it() {
        let drawn = render(Figure::InnerOuter, &DiagramOptions::new(1234)).expect("draws");
        let regions = drawn.marks.inner_regions.clone();
        let image = drawn.finish();
        // The legend swatch is the one other place the colour may appear.
        let legend_top = LEGEND_3_7_TOP as u32;
        let mut n = 0;
        for (x, y, p) in image.enumerate_pixels() {
            if [p.0[0], p.0[1], p.0[2]] != INNER || y >= legend_top {
                continue;
            }
            n += 1;
            let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            assert!(
                regions.iter().any(|r| inside(r, centre)),
                "inner colour at ({x}, {y}) outside every cut face"
            );
        }
        assert!(n > 200, "{n} inner pixels");
    }

    #[test]
    fn figure_3_7_inner_texels_store_outer_facet_tangents() {
        // The bake the figure shows, checked on its bytes: each texel inside the cut circle
        // holds the tangent of one of the facets of the segment crossing the cut height,
        // several different ones around the circle, never the axis alone.
        let options = DiagramOptions::new(1234);
        let params = FurParams {
            base_thickness: 0.12,
            tip_thickness: 0.01,
            texture_resolution: 96,
            ..base_params(&options, 20).expect("valid")
        };
        let strand = figure_strand(&params, options.seed).expect("strand");
        let chain = cones(&strand, &params);
        let h = top_height(&strand, &params);
        let n = params.number_of_shells;
        let z1 = h * (INNER_LAYER + 1) as f32 / n as f32;
        let baked = bake_shells(&params, std::slice::from_ref(&strand)).expect("bake");
        let layer = &baked.layers[INNER_LAYER as usize];
        let (centre, radius) = cross_section(&chain, z1).expect("the chain crosses z1");
        let cut = chain
            .iter()
            .find(|s| s.p0.z <= z1 && z1 <= s.p1.z)
            .expect("segment at z1");
        let table = FacetTable::new(params.circle_resolution);
        let facet_rgb: Vec<[u8; 3]> = (0..params.circle_resolution as usize)
            .map(|j| tangent_to_rgb8(cut.facet_tangent(j, &table)))
            .collect();
        let res = params.texture_resolution;
        let mut seen = Vec::new();
        for y in 0..res {
            for x in 0..res {
                let q = Vec2::new((x as f32 + 0.5) / res as f32, (y as f32 + 0.5) / res as f32);
                if q.distance(centre.truncate()) > radius * 0.9 {
                    continue;
                }
                let t = layer.tangent.get(x, y).expect("in range");
                assert!(t[3] > 0, "cut texel ({x}, {y}) not covered");
                let rgb = [t[0], t[1], t[2]];
                let close = facet_rgb.iter().position(|f| {
                    f.iter()
                        .zip(rgb)
                        .all(|(a, b)| (*a as i32 - b as i32).abs() <= 1)
                });
                let j = close.unwrap_or_else(|| {
                    panic!("({x}, {y}): {rgb:?} is no facet tangent of {facet_rgb:?}")
                });
                if !seen.contains(&j) {
                    seen.push(j);
                }
            }
        }
        assert!(seen.len() >= 4, "facets seen inside the cut: {seen:?}");
        let axis_rgb = tangent_to_rgb8(cut.axis);
        assert!(facet_rgb.iter().any(|f| *f != axis_rgb));
    }
}
