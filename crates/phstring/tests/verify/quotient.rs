//! The discrete-gradient quotient is exact to a few ulps (docs/method.md §6).
//!
//! Reference: the exact quotient `(W(C₁) − W(C₀)) / (C₁ − C₀)` of the two doubles `C₀`,
//! `C₁`, evaluated with 512-bit arithmetic (astro-float). Since `C₁ − C₀` is exact here
//! (Sterbenz), matching the quotient to `k` ulps is the directionality identity
//! `S̄ (C₁ − C₀) = 2 (W(C₁) − W(C₀))` to `k` ulps.

use astro_float::{BigFloat, Consts, RoundingMode};
use phstring::{Material, StoredEnergy};

const P: usize = 512;
const RM: RoundingMode = RoundingMode::ToEven;

fn big(x: f64) -> BigFloat {
    BigFloat::from_f64(x, P)
}

fn to_f64(x: &BigFloat) -> f64 {
    x.to_string()
        .parse()
        .expect("BigFloat prints a parseable decimal")
}

/// `W(C)` in 512-bit arithmetic.
fn w_big(m: &Material, c: f64, cc: &mut Consts) -> BigFloat {
    match m {
        Material::TensionOnlyLinear(t) if c >= 1.0 => {
            return w_big(&Material::LinearElastic(t.branch), c, cc);
        }
        Material::TensionOnlyHyperelastic(t) if c >= 1.0 => {
            return w_big(&Material::Hyperelastic(t.branch), c, cc);
        }
        Material::TensionOnlyLinear(_) | Material::TensionOnlyHyperelastic(_) => return big(0.0),
        _ => {}
    }
    let c = big(c);
    let one = big(1.0);
    let ea = big(m.ea());
    match m {
        Material::Hyperelastic(_) => {
            let ln = c.ln(P, RM, cc);
            let x = c.sub(&ln, P, RM).sub(&one, P, RM);
            ea.mul(&x, P, RM).div(&big(4.0), P, RM)
        }
        Material::LinearElastic(_) => {
            let e = c.sqrt(P, RM).sub(&one, P, RM);
            ea.mul(&e.mul(&e, P, RM), P, RM).div(&big(2.0), P, RM)
        }
        Material::StVenantKirchhoff(_) => {
            let e = c.sub(&one, P, RM);
            ea.mul(&e.mul(&e, P, RM), P, RM).div(&big(8.0), P, RM)
        }
        Material::TensionOnlyLinear(_) | Material::TensionOnlyHyperelastic(_) => {
            unreachable!("handled above")
        }
    }
}

/// Exact `W'(C)` in 512-bit arithmetic (for `C₀ = C₁`).
fn dw_big(m: &Material, c: f64) -> BigFloat {
    match m {
        Material::TensionOnlyLinear(t) if c >= 1.0 => {
            return dw_big(&Material::LinearElastic(t.branch), c);
        }
        Material::TensionOnlyHyperelastic(t) if c >= 1.0 => {
            return dw_big(&Material::Hyperelastic(t.branch), c);
        }
        Material::TensionOnlyLinear(_) | Material::TensionOnlyHyperelastic(_) => return big(0.0),
        _ => {}
    }
    let cb = big(c);
    let one = big(1.0);
    let ea = big(m.ea());
    match m {
        Material::Hyperelastic(_) => {
            ea.mul(&cb.sub(&one, P, RM), P, RM)
                .div(&cb.mul(&big(4.0), P, RM), P, RM)
        }
        Material::LinearElastic(_) => {
            let s = cb.sqrt(P, RM);
            ea.mul(&s.sub(&one, P, RM), P, RM)
                .div(&s.mul(&big(2.0), P, RM), P, RM)
        }
        Material::StVenantKirchhoff(_) => ea.mul(&cb.sub(&one, P, RM), P, RM).div(&big(4.0), P, RM),
        Material::TensionOnlyLinear(_) | Material::TensionOnlyHyperelastic(_) => {
            unreachable!("handled above")
        }
    }
}

fn ulp(x: f64) -> f64 {
    let a = x.abs();
    if a == 0.0 {
        f64::MIN_POSITIVE
    } else {
        f64::from_bits(a.to_bits() + 1) - a
    }
}

#[test]
fn quotient_directionality_to_4_ulps() {
    let mut cc = Consts::new().expect("constants cache");
    let laws = [
        Material::hyperelastic(20.0),
        Material::linear_elastic(20.0),
        Material::st_venant_kirchhoff(20.0),
        Material::tension_only_linear(20.0),
        Material::tension_only_hyperelastic(20.0),
    ];
    let mut worst = 0.0_f64;
    let mut cases = 0;
    for law in &laws {
        for c in [0.5, 1.0, 2.0] {
            // 3e-3 … 0.3 put t = ΔC/(C₀+C₁) in each range of the hyperelastic series
            // (t² up to 1e-6, 1e-3, 1e-2, 1/16, 1/4).
            for dc in [0.0, 1e-16, 1e-12, 1e-8, 1e-4, 3e-3, 0.03, 0.1, 0.3, 0.5] {
                // Forward, backward and centred pairs around C.
                for (c0, c1) in [(c, c + dc), (c, c - dc), (c - 0.5 * dc, c + 0.5 * dc)] {
                    if !(law.admissible(c0) && law.admissible(c1)) {
                        continue;
                    }
                    let (q, _) = law.quotient(c0, c1);
                    let exact = if c1 == c0 {
                        to_f64(&dw_big(law, c0))
                    } else {
                        let dw = w_big(law, c1, &mut cc).sub(&w_big(law, c0, &mut cc), P, RM);
                        to_f64(&dw.div(&big(c1).sub(&big(c0), P, RM), P, RM))
                    };
                    let err_ulps = (q - exact).abs() / ulp(exact);
                    worst = worst.max(err_ulps);
                    cases += 1;
                    assert!(
                        err_ulps <= 4.0,
                        "{}: C0 = {c0:e}, C1 = {c1:e}: q = {q:e}, exact {exact:e}, {err_ulps} ulps",
                        law.name()
                    );
                }
            }
        }
    }
    eprintln!("quotient: worst error {worst} ulps over {cases} cases");
}

/// `W(C)` itself keeps full relative accuracy near the reference strain, where it is
/// `O((C−1)²)` (needed for the tension-only law's crossing branch and for energies).
#[test]
fn stored_energy_accurate_near_reference() {
    let mut cc = Consts::new().expect("constants cache");
    let laws = [
        Material::hyperelastic(20.0),
        Material::linear_elastic(20.0),
        Material::st_venant_kirchhoff(20.0),
    ];
    let mut worst = 0.0_f64;
    for law in &laws {
        for dc in [1e-12_f64, 1e-8, 1e-4, 0.1, 0.5, 3.0] {
            for c in [1.0 + dc, 1.0 - dc.min(0.9)] {
                let exact = to_f64(&w_big(law, c, &mut cc));
                let err = (law.w(c) - exact).abs() / ulp(exact);
                worst = worst.max(err);
                assert!(
                    err <= 4.0,
                    "{}: W({c:e}) = {:e}, exact {exact:e}: {err} ulps",
                    law.name(),
                    law.w(c)
                );
            }
        }
    }
    eprintln!("W(C): worst error {worst} ulps");
}
