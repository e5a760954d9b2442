//! Elements too short for the rounding of their coordinates.
//!
//! A coordinate `x` is held to about `ε |x|` (`ε = 2.2e-16`), so an element between nodes at
//! coordinates of size `X` (the largest absolute coordinate of its two nodes) has its
//! direction vector `r_b − r_a` known to about `ε X` only, and its strain `C = |r'|²` to a
//! relative `2 ε X / ℓ` (`ℓ` its length); the interior nodes of a span are interpolated, so
//! a string starts with that much strain noise. Newton's round-off floor (docs/method.md §9)
//! assumes `C` to near `ε`: an element far shorter than `X` then has a residual that no
//! iteration can reduce, and the run fails ("line search failed … could not be reduced"),
//! while validation has nothing to object to. `check` and `run` print a warning instead.

use phstring::{Law, Material, Network, Vector};

use crate::text::num;

/// An element shorter than `ROUNDING_FACTOR · ε · X` is warned about: its strain then
/// carries a relative rounding error above `2 / ROUNDING_FACTOR = 2e-8`. Measured on a 2D
/// tension-only steel rope (EA = 1e8 N, 100 kg at its end) hanging from (1, 1) m, whose
/// first span of 4 elements is shortened, coordinates of order 1 m: with `ℓ / (ε X)` =
/// 2.8e2 (a 1e-12 m span) the run fails at step 1, with 1.1e6 at step 411, with 3.4e6 it
/// needs 357 steps where a 0.1 m span needs 10; above 1e7 the step count follows the short
/// element's stiffness, not the rounding.
pub const ROUNDING_FACTOR: f64 = 1e8;

/// `|d|` [m], without overflow or underflow of the squares (`|(1e-300, 0)|` is 1e-300,
/// not 0).
pub(super) fn length<const D: usize>(d: &Vector<D>) -> f64 {
    let m = d.amax();
    if m == 0.0 || !m.is_finite() {
        return m;
    }
    m * (d / m).norm()
}

/// One warning per string whose initial elements are shorter than [`ROUNDING_FACTOR`] times
/// the rounding of their coordinates; springs are left out. `single`: the scenario is one
/// string (`[geometry]`), not a network of named strings.
pub(super) fn short_element_warnings<const D: usize>(
    net: &Network<D, Material>,
    single: bool,
) -> Vec<String> {
    let mut out = Vec::new();
    for (k, g) in net.groups.iter().enumerate() {
        if matches!(g.law, Law::Spring(_)) {
            continue;
        }
        let mut count = 0;
        // The element with the smallest ratio ℓ / (ε X): (element, ℓ, X).
        let mut worst: Option<(usize, f64, f64)> = None;
        // The elements parked on a winch's drum are not counted (they lie at the drum).
        let parked = net
            .winches
            .iter()
            .find(|w| w.group == k)
            .map_or(0, |w| w.reserve);
        for e in g.elements.clone().skip(parked) {
            let [a, b] = net.mesh.elements()[e];
            let (ra, rb) = (&net.initial.r[a], &net.initial.r[b]);
            let size = ra.amax().max(rb.amax());
            let len = length(&(rb - ra));
            if len < ROUNDING_FACTOR * f64::EPSILON * size {
                count += 1;
                if worst.is_none_or(|(_, l, x)| len / size < l / x) {
                    worst = Some((e, len, size));
                }
            }
        }
        if let Some((e, len, size)) = worst {
            let which = if single {
                "the string".to_string()
            } else {
                format!("string \"{}\"", g.name)
            };
            out.push(format!(
                "{which}: {count} of its {} elements are shorter than {ROUNDING_FACTOR:.0e} times the rounding of their coordinates; element {e} is {} m long at coordinates of {} m, which floating point holds to about {} m, so its strain carries a relative rounding error of about {} and Newton may fail at the first step; move the coordinates' origin near the string, or use fewer, longer elements",
                g.elements.len(),
                num(len),
                num(size),
                num(f64::EPSILON * size),
                num(2.0 * f64::EPSILON * size / len)
            ));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn length_neither_overflows_nor_underflows() {
        assert_eq!(length(&Vector::<2>::new(1e-300, 0.0)), 1e-300);
        assert_eq!(length(&Vector::<2>::new(3e300, 4e300)), 5e300);
        assert_eq!(length(&Vector::<3>::new(0.0, 3.0, -4.0)), 5.0);
        assert_eq!(length(&Vector::<1>::zeros()), 0.0);
        assert_eq!(length(&Vector::<2>::new(1.7e308, 1.7e308)), f64::INFINITY);
    }
}
