//! A winch's cut in place (docs/method.md §23, "The cost of a cut"): the system's data and
//! its energies change only at the string's elements and nodes between the drum element
//! before the cut and the one after it, so a cut computes there alone, whatever the number
//! of elements (the sorted lists it changes shift their later entries in memory).

use std::ops::Range;

use crate::material::StoredEnergy;
use crate::system::{Energies, PhSystem, State, element_energies, is_held};
use crate::winch::WinchState;

/// The string-local elements and nodes a cut of winch `k` from drum element `from` to `to`
/// (indices along its string) changes: the elements from the one before the lower drum
/// element to the higher one, whose kinetic or stored energy a moved node or strain changes,
/// and the nodes between the two drum nodes, whose held flag, body force and water change.
pub(crate) fn cut_window(from: usize, to: usize) -> (Range<usize>, Range<usize>) {
    let (lo, hi) = (from.min(to), from.max(to));
    (lo.saturating_sub(1)..hi + 1, lo..hi + 1)
}

impl<const D: usize, M: StoredEnergy> PhSystem<D, M> {
    /// The part of [`Self::energies`] [J] that winch `k`'s string holds, at the system's
    /// current data, in its elements `els` (indices along the string; those on the drum hold
    /// none) and at its nodes `nodes` (indices along the string, not its last, which carry
    /// no point mass or water point: refused at setup): the elements' kinetic and stored
    /// energies, the nodes' body-force potentials and their buoyancy and contact
    /// potentials, each term evaluated as `energies` evaluates it.
    pub(crate) fn winch_energies(
        &self,
        k: usize,
        (els, nodes): (Range<usize>, Range<usize>),
        state: &State<D>,
    ) -> Energies {
        let m = &self.winches[k];
        let g = &self.groups[m.group];
        let mut out = Energies::default();
        for j in els {
            let e = m.elements.start + j;
            if !g.elements.contains(&e) {
                continue;
            }
            let [a, b] = self.mesh.elements()[e];
            let l = self.mesh.lengths()[e];
            let (t, w) = element_energies(g, l, (&state.v[a], &state.v[b]), state.c[e]);
            out.kinetic += t;
            out.internal += w;
            out.magnitude += t.abs() + w.abs();
        }
        for &i in &m.nodes[nodes] {
            let p = state.r[i].dot(&self.f_body[i]);
            out.external -= p;
            out.magnitude += p.abs();
            let Some(w) = self.water.as_deref() else {
                continue;
            };
            if let Ok(at) = w.nodes.binary_search_by_key(&i, |n| n.node) {
                let (u, c) = w.node_energies(&w.nodes[at], &state.r[i]);
                out.buoyancy += u;
                out.seabed += c;
                out.magnitude += u.abs() + c;
            }
        }
        out
    }

    /// Puts winch `k`'s state `ws`, just cut from the drum element `from` (index along its
    /// string), into the system's data as [`Self::place_winches`] would, changing only the
    /// group's range and the string's nodes and elements between the two drum elements:
    /// held flags, body forces, the constrained sets (a search and a shift each, within
    /// their capacity) and the water lumped at those nodes.
    pub(crate) fn place_cut(&mut self, k: usize, ws: &WinchState, from: usize) {
        let m = &self.winches[k];
        let (els, nodes) = cut_window(from, ws.drum);
        let range = &mut self.groups[m.group].elements;
        m.place_nodes(
            ws,
            &self.mesh,
            range,
            (&mut self.f_body, &mut self.free),
            nodes.clone(),
        );
        for &i in &m.nodes[nodes.clone()] {
            set_member(&mut self.constrained, i, is_held(&self.free[i]));
        }
        for j in els.clone() {
            let e = m.elements.start + j;
            let [a, b] = self.mesh.elements()[e];
            let held = is_held(&self.free[a]) || is_held(&self.free[b]);
            set_member(&mut self.constrained_elements, e, held);
        }
        if let (Some(w), Some(spec)) = (self.water.as_deref_mut(), self.water_spec.as_deref()) {
            let active = &self.groups[m.group].elements;
            let elements = m.elements.start + els.start..m.elements.start + els.end;
            let wet = (&spec.0, &spec.1);
            w.relump_string(
                wet,
                &self.mesh,
                (m.group, active),
                (elements, &m.nodes[nodes]),
            );
        }
        self.place_body_drum(k, ws);
    }
}

/// Puts `x` into the sorted list `list` (or takes it out) by `member`.
fn set_member(list: &mut Vec<usize>, x: usize, member: bool) {
    match (list.binary_search(&x), member) {
        (Err(at), true) => list.insert(at, x),
        (Ok(at), false) => {
            list.remove(at);
        }
        _ => {}
    }
}
