//! The extremes of every line (string) of a run, sampled at every state the run passes
//! through (`t = 0` and every step): the record behind `summary.json`'s `lines` and a
//! campaign's table (docs/moordyn.md, "Campaigns"). Plain data, carried across a resume
//! in the checkpoint.

use serde::{Deserialize, Serialize};

/// One line's extremes over a run. The tensions are the magnitudes of the forces of the
/// line on its end nodes, the values of `end_tensions.csv` (`FairTen<i>` at end B, the
/// last node of its path; `AnchTen<i>` at end A, the first).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LineExtremes {
    /// The line's name (its string's name; `lineN` for deck line N).
    pub name: String,
    /// Largest fairlead tension `FairTen` [N].
    pub fair_ten_max: f64,
    /// The time of the largest fairlead tension [s] (its first occurrence).
    pub fair_ten_max_t: f64,
    /// Smallest fairlead tension [N].
    pub fair_ten_min: f64,
    /// Largest anchor tension `AnchTen` [N].
    pub anch_ten_max: f64,
    /// Smallest anchor tension [N].
    pub anch_ten_min: f64,
    /// Smallest grounded length [m]: the line's seabed contact length (its elements'
    /// reference lengths, each counted half for each of its nodes on the seabed, as in
    /// `summary.json`'s `water`); 0 without a seabed.
    pub grounded_length_min: f64,
    /// Whether the line went slack in some state: an element shorter than its unstretched
    /// length (stretch `√C < 1`), which under the tension-only law carries no tension.
    pub slack: bool,
    /// The number of states (`t = 0` and the steps) in which it was slack.
    pub slack_steps: usize,
    /// The first time it was slack [s] (`None`: never).
    pub slack_first_t: Option<f64>,
    /// Smallest stretch `√C` of any of its elements over the run (dimensionless; below 1:
    /// slack).
    pub stretch_min: f64,
}

impl LineExtremes {
    /// The record of a line named `name` before any state is sampled (extremes at ±∞).
    pub fn new(name: &str) -> Self {
        Self {
            name: name.to_string(),
            fair_ten_max: f64::NEG_INFINITY,
            fair_ten_max_t: 0.0,
            fair_ten_min: f64::INFINITY,
            anch_ten_max: f64::NEG_INFINITY,
            anch_ten_min: f64::INFINITY,
            grounded_length_min: f64::INFINITY,
            slack: false,
            slack_steps: 0,
            slack_first_t: None,
            stretch_min: f64::INFINITY,
        }
    }

    /// Samples one state at time `t` [s]: the end tensions `fair` and `anch` [N], the
    /// grounded length [m] and the smallest stretch of the line's elements in it. A NaN
    /// is kept (a broken run cannot report a finite extreme).
    pub fn sample(&mut self, t: f64, (fair, anch): (f64, f64), grounded: f64, stretch: f64) {
        if fair > self.fair_ten_max || fair.is_nan() {
            self.fair_ten_max = fair;
            self.fair_ten_max_t = t;
        }
        self.fair_ten_min = nan_min(self.fair_ten_min, fair);
        self.anch_ten_max = -nan_min(-self.anch_ten_max, -anch);
        self.anch_ten_min = nan_min(self.anch_ten_min, anch);
        self.grounded_length_min = nan_min(self.grounded_length_min, grounded);
        self.stretch_min = nan_min(self.stretch_min, stretch);
        if stretch < 1.0 {
            self.slack = true;
            self.slack_steps += 1;
            self.slack_first_t.get_or_insert(t);
        }
    }

    /// Whether every value is finite, non-negative where it must be, and the slack fields
    /// agree with each other and with `stretch_min`, with times in `[0, t]` (the checks of
    /// a checkpoint's copy); the reason if not.
    pub fn check(&self, t: f64) -> Result<(), String> {
        let values = [
            self.fair_ten_max,
            self.fair_ten_min,
            self.anch_ten_max,
            self.anch_ten_min,
            self.grounded_length_min,
            self.stretch_min,
        ];
        if values.iter().any(|x| !x.is_finite() || *x < 0.0) {
            return Err(format!(
                "line {}: an extreme is negative or not finite",
                self.name
            ));
        }
        let times = std::iter::once(self.fair_ten_max_t).chain(self.slack_first_t);
        if times.into_iter().any(|s| !(0.0..=t).contains(&s)) {
            return Err(format!("line {}: a time is outside [0, {t}] s", self.name));
        }
        let slack = self.slack_steps > 0;
        if self.slack != slack
            || self.slack_first_t.is_some() != slack
            || (self.stretch_min < 1.0) != slack
        {
            return Err(format!(
                "line {}: slack, slack_steps, slack_first_t and stretch_min disagree",
                self.name
            ));
        }
        Ok(())
    }
}

/// The smaller of `a` and `b`, NaN if either is (`f64::min` would drop it).
fn nan_min(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.min(b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three states of a line: the extremes, the time of the largest fairlead tension (its
    /// first occurrence), and slack from the state whose stretch is below 1.
    #[test]
    fn samples_keep_the_extremes_and_the_slack_states() {
        let mut x = LineExtremes::new("line1");
        x.sample(0.0, (1.2e6, 0.9e6), 300.0, 1.002);
        x.sample(0.5, (1.5e6, 0.7e6), 280.0, 0.9995);
        x.sample(1.0, (1.5e6, 1.1e6), 310.0, 1.001);
        assert_eq!((x.fair_ten_max, x.fair_ten_max_t), (1.5e6, 0.5));
        assert_eq!(
            (x.fair_ten_min, x.anch_ten_max, x.anch_ten_min),
            (1.2e6, 1.1e6, 0.7e6)
        );
        assert_eq!((x.grounded_length_min, x.stretch_min), (280.0, 0.9995));
        assert!(x.slack);
        assert_eq!((x.slack_steps, x.slack_first_t), (1, Some(0.5)));
        assert_eq!(x.check(1.0), Ok(()));
        assert!(x.check(0.4).unwrap_err().contains("outside [0, 0.4]"));
        let mut y = x.clone();
        y.slack_steps = 0;
        assert!(y.check(1.0).unwrap_err().contains("disagree"));
        x.sample(1.5, (f64::NAN, 1.0e6), 300.0, 1.0);
        assert!(x.fair_ten_max.is_nan() && x.fair_ten_min.is_nan());
        assert!(x.check(2.0).is_err());
    }
}
