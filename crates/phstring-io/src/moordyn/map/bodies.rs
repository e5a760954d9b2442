//! The BODIES of a deck (docs/moordyn.md, "Bodies"): a free body becomes a `[bodies.bodyN]`
//! with its mass, inertia, pose, volume, drag area and added mass (MoorDyn's about the
//! reference point, moved to the centre of mass); a coupled body a prescribed one (held at
//! its deck pose, or moved by a `--motion` platform table); a fixed body's points fixed
//! supports. Its points (`BodyN` in POINTS) are the body's points `bodyN.pK` (or, on a fixed
//! body, nodes `pointK`), placed at `X0 + R p`. What the body model does not take
//! (rotational or per-axis drag, pinned bodies) is refused with the deck's line.

use std::fmt::Write as _;

use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

use super::{Feature, Mapper, f, q};
use crate::moordyn::error::DeckError;
use crate::moordyn::{Body, BodyKind, Point};

/// The deck body's reference point [m] and rotation `R = Rx(r0) Ry(p0) Rz(y0)`.
fn frame(b: &Body) -> (Vector3<f64>, Matrix3<f64>) {
    let deg = std::f64::consts::PI / 180.0;
    let [x, y, z, r, p, w] = b.pose;
    (
        Vector3::new(x, y, z),
        phstring::signal::rotation(r * deg, p * deg, w * deg),
    )
}

/// The centre of gravity relative to the reference point, body axes [m] (one value: along
/// z).
fn cg(b: &Body) -> Vector3<f64> {
    match b.cg[..] {
        [z] => Vector3::new(0.0, 0.0, z),
        [x, y, z] => Vector3::new(x, y, z),
        _ => Vector3::zeros(),
    }
}

/// Point `p`, attached to body `n` and on a line: its place and name. On a fixed body it is
/// a fixed support `pointK` at `X0 + R p` (the text written here); on a free or coupled
/// body it is the body point `bodyN.pK`, written with its body ([`bodies`]). Returns what it
/// became.
pub(super) fn body_point(m: &mut Mapper, p: &Point, n: u32) -> Result<String, DeckError> {
    let entry = format!("point {} ({})", p.id, p.kind_text);
    let Some(body) = m.deck.bodies.get(n as usize - 1).cloned() else {
        return m.unmappable(
            p.line,
            format!(
                "{entry} is attached to body {n}, but the deck has {} bodies",
                m.deck.bodies.len()
            ),
        );
    };
    let (x0, rot) = frame(&body);
    let at = x0 + rot * Vector3::from(p.position);
    let at = [at.x, at.y, at.z];
    if p.mass != 0.0 || p.volume != 0.0 || p.cda != 0.0 || p.ca != 0.0 {
        m.unsupported(
            p.line,
            format!("the mass, volume, CdA or Ca of {entry} (a point fixed to body {n})"),
            Feature::Bodies,
        )?;
    }
    match body.kind {
        BodyKind::Fixed => {
            let name = format!("point{}", p.id);
            let _ = write!(
                m.text,
                "# {}: {entry}, on fixed body {n}\n[[node]]\nname = {}\nposition = [{}, {}, {}]\n\n[[boundary]]\nnode = {}\nfixed = true\n\n",
                m.at(p.line),
                q(&name),
                f(at[0]),
                f(at[1]),
                f(at[2]),
                q(&name)
            );
            m.placed.insert(p.id, (name.clone(), at));
            Ok(format!(
                "node {name}, a fixed support at X0 + R p of fixed body {n}"
            ))
        }
        BodyKind::Pinned => m.refuse(
            body.line,
            format!(
                "body {n} ({}), coupled in translation and free to turn: MoorDyn moves its reference point with the vessel and turns it under the moments about that point; phstring's body is free, or prescribed as a whole (`motion` and `motion_table` give the whole pose, and without an orientation it keeps its own), so it cannot hold the translation and leave the rotation free",
                body.kind_text
            ),
        ),
        BodyKind::Free | BodyKind::Coupled => {
            let name = format!("body{n}.p{}", p.id);
            m.placed.insert(p.id, (name.clone(), at));
            m.members.entry(n).or_default().push((p.id, p.position));
            Ok(format!("body point {name} of [bodies.body{n}]"))
        }
    }
}

/// The free and coupled bodies that hold points on lines: one `[bodies.bodyN]` each (a free
/// body's added mass with the water's density `rho_w` [kg/m³]); the others a row saying
/// what they became.
pub(super) fn bodies(m: &mut Mapper, rho_w: f64) -> Result<(), DeckError> {
    let list = m.deck.bodies.clone();
    for b in &list {
        let entry = format!("body {} ({})", b.id, b.kind_text);
        let members = m.members.get(&b.id).cloned().unwrap_or_default();
        if b.kind == BodyKind::Fixed {
            m.row(
                b.line,
                entry,
                "its points are fixed supports (a fixed body)",
            );
            continue;
        }
        if members.is_empty() {
            m.row(b.line, entry, "nothing (no line ends at one of its points)");
            continue;
        }
        let became = match b.kind {
            BodyKind::Free => free_body(m, b, &members, rho_w)?,
            _ => coupled_body(m, b, &members)?,
        };
        m.row(b.line, entry, became);
    }
    Ok(())
}

/// `points = { pK = [x, y, z], … }` of `members` relative to `origin` (body axes) [m].
fn points_text(members: &[(u32, [f64; 3])], origin: &Vector3<f64>) -> String {
    let list: Vec<String> = members
        .iter()
        .map(|(id, p)| {
            let s = Vector3::from(*p) - origin;
            format!("p{id} = [{}, {}, {}]", f(s.x), f(s.y), f(s.z))
        })
        .collect();
    format!("{{ {} }}", list.join(", "))
}

/// A free body: mass, inertia about the centre of gravity, its pose (the centre at
/// `X0 + R CG`), its points relative to the centre, its volume (buoyancy at the centre, as
/// MoorDyn has it), a translational drag area and its added mass in water of density
/// `rho_w` [kg/m³] ([`added_mass`]); rotational and per-axis drag are refused (or dropped
/// with `--ignore bodies`).
fn free_body(
    m: &mut Mapper,
    b: &Body,
    members: &[(u32, [f64; 3])],
    rho_w: f64,
) -> Result<String, DeckError> {
    if b.mass <= 0.0 {
        return m.unmappable(
            b.line,
            format!(
                "free body {} has Mass {} kg: phstring's bodies need a positive mass",
                b.id, b.mass
            ),
        );
    }
    let inertia = match b.inertia[..] {
        [i] => [i; 3],
        [x, y, z] => [x, y, z],
        _ => [0.0; 3],
    };
    if inertia.iter().any(|i| *i <= 0.0) {
        return m.unmappable(
            b.line,
            format!("free body {} has the moments of inertia I = {inertia:?} kg·m²: each must be positive", b.id),
        );
    }
    if b.volume < 0.0 {
        return m.unmappable(
            b.line,
            format!("free body {} has a negative Volume {} m³", b.id, b.volume),
        );
    }
    let cda = drag_area(m, b)?;
    let added = added_mass(m, b, rho_w)?;
    let (x0, rot) = frame(b);
    let c = cg(b);
    let centre = x0 + rot * c;
    let _ = write!(
        m.text,
        "# {}: body {} ({})\n[bodies.body{}]\nmass = {}\ninertia = [{}, {}, {}]\nposition = [{}, {}, {}]\norientation = [{}, {}, {}]\npoints = {}\n",
        m.at(b.line),
        b.id,
        b.kind_text,
        b.id,
        f(b.mass),
        f(inertia[0]),
        f(inertia[1]),
        f(inertia[2]),
        f(centre.x),
        f(centre.y),
        f(centre.z),
        f(b.pose[3]),
        f(b.pose[4]),
        f(b.pose[5]),
        points_text(members, &c)
    );
    if b.volume > 0.0 {
        let _ = writeln!(m.text, "volume = {}", f(b.volume));
    }
    if cda > 0.0 {
        let _ = writeln!(m.text, "cda = {}", f(cda));
        m.converted(b.line, format!("CdA = {cda} m² of body {}: MoorDyn's body drag is ½ρ_w CdA |v_r| v_r at the reference point (v_r the reference point's velocity relative to the water), phstring's the same at the centre of mass: equal when the centre of gravity is at the reference point or the body does not turn", b.id));
    }
    let added = added.map_or_else(String::new, |a| {
        let _ = writeln!(m.text, "{}", a.key);
        format!(", {}", a.row)
    });
    m.text.push('\n');
    Ok(format!(
        "[bodies.body{}]: a free rigid body of {} kg, inertia {inertia:?} kg·m², centre at {:?} m (X0 + R CG), volume {} m³ (buoyancy at the centre of mass, as MoorDyn's), CdA {cda} m²{added}, points {}",
        b.id,
        b.mass,
        [centre.x, centre.y, centre.z],
        b.volume,
        members
            .iter()
            .map(|(id, _)| format!("p{id}"))
            .collect::<Vec<_>>()
            .join(", ")
    ))
}

/// `values` as the deck writes them, `a|b|c`.
fn joined(values: &[f64]) -> String {
    let v: Vec<String> = values.iter().map(|c| c.to_string()).collect();
    v.join("|")
}

/// The translational drag area [m²] of body `b`'s `CdA` column, read as MoorDyn 2.7.2 reads
/// it (`MoorDyn::readBody`): one value for all six degrees of freedom; two, translation and
/// rotation; three, per body axis for both; six, per degree of freedom; of three or six
/// values the first (x) is read as 0 (its loop starts at the second value). Its rotational
/// drag must be zero and its translational drag the same on every axis (else refused, or
/// dropped with `--ignore bodies`).
fn drag_area(m: &mut Mapper, b: &Body) -> Result<f64, DeckError> {
    let (t, r): ([f64; 3], [f64; 3]) = match b.cda[..] {
        [a] => ([a; 3], [a; 3]),
        [a, c] => ([a; 3], [c; 3]),
        [_, y, z] => ([0.0, y, z], [0.0, y, z]),
        [_, y, z, rx, ry, rz] => ([0.0, y, z], [rx, ry, rz]),
        _ => ([0.0; 3], [0.0; 3]),
    };
    let written = joined(&b.cda);
    if b.cda.iter().any(|c| *c < 0.0) {
        return m.unmappable(
            b.line,
            format!("body {} has a negative drag area CdA = {written} m²", b.id),
        );
    }
    let dropped = if b.cda.len() >= 3 && b.cda[0] != 0.0 {
        format!(
            "; MoorDyn 2.7.2 reads the first of {} CdA values as 0",
            b.cda.len()
        )
    } else {
        String::new()
    };
    if r.iter().any(|c| *c != 0.0) {
        m.unsupported(
            b.line,
            format!(
                "the rotational drag of body {} (CdA = {written}, which MoorDyn reads as the rotational drag areas {r:?}: the moment −½ρ_w R diag(CdA_r) Rᵀ |ω| ω about the reference point, ω the body's angular velocity{dropped}; phstring's body has no rotational quadratic drag, only the translational ½ρ_w CdA |v_r| v_r and a linear drag at the centre of mass; give `CdA|0` for translational drag alone)",
                b.id
            ),
            Feature::Bodies,
        )?;
    }
    if t.iter().any(|c| *c != t[0]) {
        m.unsupported(
            b.line,
            format!(
                "the per-axis drag areas of body {} (CdA = {written}, which MoorDyn reads as {t:?} m² along the body axes{dropped}; phstring's body has one drag area for every direction)",
                b.id
            ),
            Feature::Bodies,
        )?;
        return Ok(0.0);
    }
    Ok(t[0])
}

/// What a free body's added mass became: the scenario's line (`ca = …` or the
/// `added_mass` matrix) and the words of its `check` row.
struct Added {
    key: String,
    row: String,
}

/// The added mass of free body `b` from its `Ca` column in water of density `rho_w`
/// [kg/m³]. MoorDyn 2.7.2 (`Body::setup`) adds `ρ_w V Ca_i` [kg] to the translational
/// diagonal of the body's mass matrix about its reference point in body axes, one value for
/// the three axes or three per axis (`MoorDyn::readBody` refuses other counts; no rotational
/// added mass comes from `Ca`). That matrix is moved to the centre of mass by the CG offset
/// ([`phstring::added_mass_about_centre`]): `ca` when it is one value and the CG is at the
/// reference point, else the 6×6 `added_mass`. `None`: no added mass (`Ca` 0, or no volume).
fn added_mass(m: &mut Mapper, b: &Body, rho_w: f64) -> Result<Option<Added>, DeckError> {
    let written = joined(&b.ca);
    let ca = match b.ca[..] {
        [a] => [a; 3],
        [x, y, z] => [x, y, z],
        _ => {
            return m.unmappable(
                b.line,
                format!(
                    "body {} has {} added-mass coefficients Ca = {written}: MoorDyn reads 1 (all three axes) or 3 (per body axis), translational only, and refuses this deck",
                    b.id,
                    b.ca.len()
                ),
            );
        }
    };
    if ca.iter().any(|c| *c < 0.0) {
        return m.unmappable(
            b.line,
            format!(
                "body {} has a negative added-mass coefficient Ca = {written}",
                b.id
            ),
        );
    }
    if ca == [0.0; 3] {
        return Ok(None);
    }
    if b.volume == 0.0 {
        m.converted(b.line, format!("Ca = {written} of body {} adds nothing: MoorDyn's body added mass is ρ_w V Ca, and its Volume is 0", b.id));
        return Ok(None);
    }
    let a = ca.map(|c| rho_w * b.volume * c);
    let c = cg(b);
    m.converted(b.line, format!("Ca = {written} of body {}: MoorDyn's added mass ρ_w V Ca = {a:?} kg along the body axes at the reference point, moved to the centre of mass (the same kinetic energy); the motions agree while the body does not turn, and when it turns MoorDyn's body equations keep of the velocity terms only −M_tt ω×(ω×R CG), phstring's are those of the whole kinetic energy", b.id));
    if ca[0] == ca[1] && ca[1] == ca[2] && c == Vector3::zeros() {
        return Ok(Some(Added {
            key: format!("ca = {}", f(ca[0])),
            row: format!("added mass Ca ρ_w V = {} kg in every direction", a[0]),
        }));
    }
    let a_o = Matrix6::from_diagonal(&Vector6::new(a[0], a[1], a[2], 0.0, 0.0, 0.0));
    let a_c = phstring::added_mass_about_centre(&a_o, &c);
    let rows: Vec<String> = a_c
        .row_iter()
        .map(|r| {
            let v: Vec<String> = r.iter().map(|x| f(*x)).collect();
            format!("    [{}],", v.join(", "))
        })
        .collect();
    Ok(Some(Added {
        key: format!("added_mass = [\n{}\n]", rows.join("\n")),
        row: format!(
            "added mass ρ_w V Ca = {a:?} kg along the body axes at the reference point, moved to the centre of mass (added_mass, 6×6, with the lever CG = {:?} m)",
            [c.x, c.y, c.z]
        ),
    }))
}

/// A coupled body: a prescribed one, held at its deck pose or moved by the `--motion`
/// platform table (its pose is the table's, its points at their deck coordinates from the
/// reference point); its mass and inertia are 1 kg and 1 kg·m² (MoorDyn's coupled body has
/// none; phstring's needs some, which enters only its reaction).
fn coupled_body(
    m: &mut Mapper,
    b: &Body,
    members: &[(u32, [f64; 3])],
) -> Result<String, DeckError> {
    let at = m.at(b.line);
    let points = points_text(members, &Vector3::zeros());
    let head = format!(
        "# {at}: body {} ({})\n[bodies.body{}]\nmass = 1.0\ninertia = [1.0, 1.0, 1.0]\npoints = {points}\n",
        b.id, b.kind_text, b.id
    );
    m.converted(b.line, format!("coupled body {} carries 1 kg and 1 kg·m² (MoorDyn's coupled body has no mass; phstring's prescribed body needs one, which enters only its reaction)", b.id));
    match m.motion {
        Some(mv) if mv.points.is_none() => {
            if !m.coupled_bodies.is_empty() {
                return m.unmappable(
                    b.line,
                    format!("body {} is a second coupled body, but --motion gives one platform table (one rigid motion)", b.id),
                );
            }
            m.coupled_bodies.push(b.id);
            let (p, _) = &mv.start;
            let _ = write!(
                m.text,
                "{head}position = [{}, {}, {}]\nmotion_table = {}\n\n",
                f(p[0]),
                f(p[1]),
                f(p[2]),
                q(&mv.path.display().to_string())
            );
            Ok(format!(
                "[bodies.body{}]: a prescribed body moved by the --motion platform table (its reference point and orientation), reaction force and torque out",
                b.id
            ))
        }
        Some(mv) => m.unmappable(
            b.line,
            format!(
                "coupled body {} needs a platform table (7 columns: t, x, y, z, roll, pitch, yaw), but --motion {} is a per-point table",
                b.id,
                mv.path.display()
            ),
        ),
        None => {
            m.coupled_bodies.push(b.id);
            let [x, y, z, r, p, w] = b.pose;
            let _ = write!(
                m.text,
                "{head}position = [{}, {}, {}]\norientation = [{}, {}, {}]\nmotion = {{ position = [{}, {}, {}], orientation = [{}, {}, {}] }}\n\n",
                f(x),
                f(y),
                f(z),
                f(r),
                f(p),
                f(w),
                q(&f(x)),
                q(&f(y)),
                q(&f(z)),
                q(&f(r)),
                q(&f(p)),
                q(&f(w))
            );
            m.converted(b.line, format!("coupled body {} is held at its deck pose: without a vessel motion a coupled body does not move", b.id));
            Ok(format!(
                "[bodies.body{}]: a prescribed body held at its deck pose (no vessel motion), reaction force and torque out",
                b.id
            ))
        }
    }
}
