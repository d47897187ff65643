//! How much to render: the internal resolution while the view changes, and the refinement steps
//! when it stops. Pure functions, so the policy is tested without threads or a window.
//!
//! While the camera moves (or time runs with wind or fire), frames are drawn at 1/d of the
//! window size, d a power of two adapted after every frame so a frame takes about
//! [`FRAME_BUDGET_MS`]. Once the view has stayed the same for [`SETTLE_MS`], it is drawn again
//! at 1/(d/2), 1/(d/4), … down to full size, each shown as soon as it is done.

/// Aimed-for time of one interactive frame, milliseconds.
pub const FRAME_BUDGET_MS: f64 = 70.0;
/// How long the view must stay the same before refinement starts, milliseconds.
pub const SETTLE_MS: u128 = 250;
/// The coarsest internal resolution: 1/16 of the window size.
pub const MAX_DIVISOR: u32 = 16;
/// A measured frame time is trusted for this many frames, then measured again.
const MEMORY_FRAMES: u64 = 120;
/// Without a recent measurement, the next finer size (four times the pixels) is guessed to
/// take this many times as long: less than four, as part of a frame's cost does not depend on
/// its size (vertices, binning, fins).
const FINER_GUESS: f64 = 2.0;

/// The image size at 1/`divisor` of `width` × `height` (rounded up, at least 1×1).
pub fn reduced_size(width: u32, height: u32, divisor: u32) -> (u32, u32) {
    let d = divisor.max(1);
    (width.div_ceil(d).max(1), height.div_ceil(d).max(1))
}

/// The interactive divisor, adapted to the measured frame times.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pace {
    divisor: u32,
    frames: u64,
    /// Per divisor 1, 2, 4, 8, 16: the last frame time and the frame count when measured.
    measured: [Option<(f64, u64)>; 5],
}

impl Default for Pace {
    /// Starts at 1/8: small enough for the slowest scenes' first frame to come quickly.
    fn default() -> Self {
        Pace {
            divisor: 8,
            frames: 0,
            measured: [None; 5],
        }
    }
}

impl Pace {
    /// The current divisor (1, 2, 4, 8 or 16).
    pub fn divisor(&self) -> u32 {
        self.divisor
    }

    /// Takes a frame drawn at 1/`divisor` in `ms` milliseconds into account, one step at a
    /// time: coarser when it took over 1.5 budgets, or over one budget while the coarser size
    /// recently kept within it; finer when the finer size is expected within the budget (its
    /// own recent time if there is one, else [`FINER_GUESS`] times this one). A size found too
    /// slow is tried again only after [`MEMORY_FRAMES`] frames, so steady frame times settle.
    pub fn observe(&mut self, divisor: u32, ms: f64) {
        if divisor != self.divisor || !ms.is_finite() {
            return;
        }
        self.frames += 1;
        self.measured[slot(divisor)] = Some((ms, self.frames));
        let recent = |d: u32| {
            self.measured[slot(d)]
                .filter(|&(_, at)| self.frames - at < MEMORY_FRAMES)
                .map(|(m, _)| m)
        };
        let coarser_fits = recent(divisor * 2).is_some_and(|m| m <= FRAME_BUDGET_MS);
        if divisor < MAX_DIVISOR
            && (ms > 1.5 * FRAME_BUDGET_MS || ms > FRAME_BUDGET_MS && coarser_fits)
        {
            self.divisor *= 2;
        } else if divisor > 1 && recent(divisor / 2).unwrap_or(ms * FINER_GUESS) <= FRAME_BUDGET_MS
        {
            self.divisor /= 2;
        }
    }
}

/// Index of a divisor (1, 2, 4, 8, 16) in [`Pace`]'s measurements.
fn slot(divisor: u32) -> usize {
    (divisor.trailing_zeros() as usize).min(4)
}

/// The refinement steps after a frame at 1/`shown`: each halving of the divisor down to 1.
pub fn refine_steps(shown: u32) -> Vec<u32> {
    let mut steps = Vec::new();
    let mut d = shown;
    while d > 1 {
        d /= 2;
        steps.push(d);
    }
    steps
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reduced_sizes_round_up_and_never_vanish() {
        assert_eq!(reduced_size(640, 480, 1), (640, 480));
        assert_eq!(reduced_size(640, 480, 8), (80, 60));
        assert_eq!(reduced_size(1366, 768, 16), (86, 48));
        assert_eq!(reduced_size(3, 1, 16), (1, 1));
        assert_eq!(reduced_size(3, 1, 0), (3, 1));
    }

    #[test]
    fn slow_frames_coarsen_and_fast_frames_refine_one_step_at_a_time() {
        let mut pace = Pace::default();
        pace.observe(8, 200.0);
        assert_eq!(pace.divisor(), 16);
        pace.observe(16, 500.0);
        assert_eq!(pace.divisor(), MAX_DIVISOR);
        // A result for another divisor (an older request) does not count.
        pace.observe(4, 1.0);
        assert_eq!(pace.divisor(), MAX_DIVISOR);
        let mut pace = Pace::default();
        // In the band between the two thresholds, it stays.
        pace.observe(8, 40.0);
        assert_eq!(pace.divisor(), 8);
        for _ in 0..10 {
            let d = pace.divisor();
            pace.observe(d, 1.0);
        }
        assert_eq!(pace.divisor(), 1);
    }

    #[test]
    fn a_size_measured_too_slow_is_not_retried_until_its_time_is_old() {
        let mut pace = Pace::default();
        pace.observe(8, 20.0); // 1/4 guessed at 40 ms: try it
        assert_eq!(pace.divisor(), 4);
        pace.observe(4, 80.0); // over budget while 1/8 fits: back
        assert_eq!(pace.divisor(), 8);
        for _ in 0..MEMORY_FRAMES - 1 {
            pace.observe(8, 20.0);
            assert_eq!(pace.divisor(), 8, "1/4 took 80 ms a moment ago");
        }
        pace.observe(8, 20.0);
        assert_eq!(
            pace.divisor(),
            4,
            "measured again once the old time has expired"
        );
    }

    #[test]
    fn steady_frame_times_settle_on_one_size() {
        // A renderer costing 15 ms a frame plus 1 ms per 1000 pixels at 640×480.
        let cost = |d: u32| {
            let (w, h) = reduced_size(640, 480, d);
            15.0 + f64::from(w * h) / 1000.0
        };
        let mut pace = Pace::default();
        let mut seen = Vec::new();
        for _ in 0..40 {
            let d = pace.divisor();
            pace.observe(d, cost(d));
            seen.push(pace.divisor());
        }
        assert!(seen[10..].iter().all(|&d| d == seen[39]), "{seen:?}");
        assert_eq!(seen[39], 4, "{seen:?}");
        assert!(cost(4) <= FRAME_BUDGET_MS && cost(2) > FRAME_BUDGET_MS);
    }

    #[test]
    fn refinement_halves_down_to_full_size() {
        assert_eq!(refine_steps(8), vec![4, 2, 1]);
        assert_eq!(refine_steps(1), Vec::<u32>::new());
    }
}
