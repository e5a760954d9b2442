//! Network solver for meshes of strings joined at junction nodes: block Thomas along each
//! string segment, a block sparse LU on the (small) reduced system of the junction nodes.
//!
//! The mesh is decomposed once, at construction, into *junction* nodes and *segments*
//! (paths junction – interior – … – interior – junction; see [`NetworkSolver`]). Per solve,
//! the interior nodes of every segment are eliminated with block Thomas (closed-form `D×D`
//! inverses, no pivoting between blocks, as [`super::BlockTridiagonal`]), which adds
//! Schur-complement blocks to the junction rows; the reduced junction system is solved with
//! a sparse LU whose symbolic analysis was done at construction ([`super::block_lu`] by
//! default, faer's scalar sparse LU on request), or block by block when no segment couples
//! two junctions, and the interior nodes are recovered by back substitution.
//!
//! With a border (the rigid bodies' slots, [`NetworkSolver::with_border`]), the slots are
//! unknowns of the reduced system too, and every node a slot couples with is made a junction
//! (docs/method.md §22): a body costs a few blocks of the reduced system, not a sweep of the
//! strings per slot component as in [`super::Bordered`].

use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::lu::LuSymbolicParams;
use nalgebra::SVector;

use super::block_lu::{BlockLu, Slot};
use super::sparse_lu::FaerBlockLu;
use super::{Block, BlockJacobian, BorderPattern, LinearSolver};
use crate::error::{LinearSolveError, SetupError};
use crate::mesh::Mesh;

/// Which sparse LU factors the reduced junction system of a [`NetworkSolver`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum JunctionLu {
    /// The crate's block sparse LU ([`super::block_lu`]): `D×D` blocks per junction, AMD
    /// ordering and symbolic factorization at construction, supernodal multifrontal numeric
    /// factorization with faer's dense kernels, no pivoting between blocks (`D×D` pivots
    /// inverted in closed form, like along the segments), no allocation per solve. On the
    /// 2 700 junctions of the 100-string benchmark net (`D = 3`) it factors in about 3 ms,
    /// against 100 ms for faer's simplicial and 15 ms for faer's supernodal scalar LU (which
    /// allocates in every factorization).
    #[default]
    Block,
    /// faer's simplicial (column-by-column) scalar LU with row pivoting, as a reference. Its
    /// storage is sized once, in the construction, so that solves do not allocate (unless
    /// row pivoting changes the fill, which it does not for diagonally dominant matrices).
    /// Slow when the junctions form a 2-D grid with thousands of nodes, whose factors fill
    /// in.
    Simplicial,
}

/// Marks a node that is not a junction in [`NetworkSolver::junction_index`].
const NOT_A_JUNCTION: usize = usize::MAX;

/// A path junction – interior – … – interior – junction of the element graph.
#[derive(Debug, Clone, Copy)]
struct Segment {
    /// End junctions `[start, end]` (node indices; equal for a loop).
    ends: [usize; 2],
    /// First interior node in `interior_nodes` (and row of the `c`, `g` workspaces).
    first_interior: usize,
    /// Number of interior nodes `m`; the segment has `m + 1` elements.
    n_interior: usize,
    /// First element of the path in `path_elements`.
    first_element: usize,
    /// Index of the segment among the non-loop segments (which own coupling blocks
    /// `(start, end)` and `(end, start)` in the reduced system); [`NOT_A_JUNCTION`] for a
    /// loop, whose couplings are diagonal.
    coupling: usize,
}

/// The reduced junction system and its LU (absent if the mesh has no junctions).
#[allow(clippy::large_enum_variant)] // one per solver, moved twice per solve
enum Reduced<const D: usize> {
    Block {
        lu: BlockLu<D>,
        /// Storage of the coupling blocks `[(start, end), (end, start)]` per non-loop
        /// segment.
        slots: Vec<[Slot; 2]>,
    },
    Faer(FaerReduced),
}

/// The reduced junction system as a scalar CSC matrix for faer's sparse LU: `D²` slots per
/// diagonal block (junctions, then border slots), then `2·D²` per pair (blocks `(a, b)` and
/// `(b, a)`; the non-loop segments' `(start, end)` first).
struct FaerReduced {
    lu: FaerBlockLu,
    /// Rows of the reduced system, in blocks.
    n_blocks: usize,
}

impl<const D: usize> Reduced<D> {
    /// Sets the matrix to zero.
    fn clear(&mut self) {
        match self {
            Reduced::Block { lu, .. } => lu.clear(),
            Reduced::Faer(red) => red.lu.clear(),
        }
    }

    /// Adds the blocks `[(a, b), (b, a)]` of pair `[a, b]` number `pair` (the non-loop
    /// segments' pairs first, numbered as their `coupling`, then the border's).
    #[inline]
    fn add_coupling(&mut self, pair: usize, blocks: &[Block<D>; 2]) {
        self.add_half(pair, 0, &blocks[0]);
        self.add_half(pair, 1, &blocks[1]);
    }

    /// Adds `blk` to block `(a, b)` (`half = 0`) or `(b, a)` (`half = 1`) of pair `[a, b]`
    /// number `pair`.
    #[inline]
    fn add_half(&mut self, pair: usize, half: usize, blk: &Block<D>) {
        match self {
            Reduced::Block { lu, slots } => lu.add(slots[pair][half], blk),
            Reduced::Faer(red) => red.lu.add((red.n_blocks + 2 * pair + half) * D * D, blk),
        }
    }

    /// Adds `blk` to the diagonal block of row `r` of the reduced system.
    #[inline]
    fn add_diag(&mut self, r: usize, blk: &Block<D>) {
        match self {
            Reduced::Block { lu, .. } => lu.add_diag(r, blk),
            Reduced::Faer(red) => red.lu.add(r * D * D, blk),
        }
    }
}

impl FaerReduced {
    /// The reduced system of `nj` diagonal blocks and the coupling blocks of `pairs`, with
    /// its symbolic simplicial LU.
    fn new<const D: usize>(nj: usize, pairs: &[[usize; 2]]) -> Self {
        let params = LuSymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
            ..Default::default()
        };
        Self {
            lu: FaerBlockLu::new::<D>(nj, pairs, params, true),
            n_blocks: nj,
        }
    }
}

/// Network linear solver for the Newton matrix of any mesh, fastest for meshes made of long
/// strings joined at few junction nodes (nets, stars, strings with springs between them).
///
/// **Decomposition** (once, in [`NetworkSolver::new`], independent of the node numbering up
/// to the choice of one node per ring): a node is *interior* if it has exactly two incident
/// elements and they lead to two distinct other nodes; every other node (ends of strings,
/// nodes of degree ≥ 3, isolated nodes, nodes with parallel elements) is a *junction*. A
/// closed ring of interior nodes without any junction gets one junction declared on it (its
/// first node met in element order). The elements then split into *segments*: maximal paths
/// junction – interior – … – interior – junction, with zero or more interior nodes; both ends
/// may be the same junction (a loop).
///
/// **Solve**: along each segment, interior node `p_k` (path order, `p_0` and `p_{m+1}` the
/// end junctions) has the row `B_{k−1} x_{p_{k−1}} + D_k x_{p_k} + F_k x_{p_{k+1}} = b_k`
/// with `F_k = ∂R_{p_k}/∂x_{p_{k+1}}` and `B_k = ∂R_{p_{k+1}}/∂x_{p_k}` taken from the element
/// blocks in path direction. Eliminating `p_1 … p_m` in order gives
/// `x_{p_k} = y_k − C_k x_{p_{k+1}} − G_k x_{p_0}` and adds Schur-complement blocks to the
/// rows of the two end junctions (diagonal, coupling and right-hand side). The reduced system
/// on the junctions is solved by a sparse LU ([`JunctionLu`], by default the crate's block
/// LU; symbolic analysis at construction, numeric refactorization per call), then the
/// interior nodes are back-substituted. When no segment couples its two end junctions and
/// there is no border (every string has an end at a support fixed in every direction, whose
/// rows and columns are the identity's: a mooring deck's lines), the reduced system is block
/// diagonal and each junction is solved with its own block's inverse instead. Pivot blocks
/// are inverted in closed form without pivoting between blocks, which is safe for the
/// mass-dominated Newton matrices of the time stepper; [`super::SparseLu`] is the oracle.
///
/// **Border** ([`NetworkSolver::with_border`]): the slots of a [`super::Border`] (unknowns
/// `n_nodes..`, the rigid bodies') are rows of the reduced system after the junctions, with
/// the blocks of the [`BorderPattern`] between them and the nodes they couple with, which
/// the decomposition makes junctions. The segments' elimination is unchanged (no slot
/// couples with an interior node), so the border adds `O(1)` blocks per body to the reduced
/// system and nothing to the sweeps along the strings.
///
/// All workspace is allocated in [`NetworkSolver::new`]; [`LinearSolver::solve`] does not
/// allocate (faer's dense kernels keep one thread-local work space, sized by a warm-up in
/// the construction; a solver moved to another thread sizes it there in its first solve).
/// A singular pivot block or a non-finite solution is reported as
/// [`LinearSolveError::Singular`] with the node index.
pub struct NetworkSolver<const D: usize> {
    /// Junction nodes, in the order of the reduced system.
    junctions: Vec<usize>,
    /// Position of each node in `junctions`, [`NOT_A_JUNCTION`] for interior nodes.
    junction_index: Vec<usize>,
    segments: Vec<Segment>,
    /// Interior nodes of all segments, segment by segment in path order.
    interior_nodes: Vec<usize>,
    /// Elements of all segments in path order, with whether element `[a, b]` is traversed
    /// `a → b` (`true`) or `b → a`.
    path_elements: Vec<(usize, bool)>,
    /// `[C_k, G_k]` per interior node (indexed like `interior_nodes`): `C_k = D'_k⁻¹ F_k`,
    /// `G_k = D'_k⁻¹ L_k` with `L_k` the fill coupling to the start junction.
    cg: Vec<[Block<D>; 2]>,
    /// Schur-complemented junction diagonal blocks (indexed like `junctions`).
    jdiag: Vec<Block<D>>,
    reduced: Option<Reduced<D>>,
    /// Number of nodes.
    n_nodes: usize,
    /// Number of border slots.
    n_slots: usize,
    /// The Newton vector's index of each row of the reduced system: the junctions, then the
    /// slots.
    rows: Vec<usize>,
    /// Per `[node, slot]` of the border's pattern (sorted, distinct), its pair in the reduced
    /// system.
    link_pairs: Vec<([usize; 2], usize)>,
    /// Per slot block `(s, t)`, `s ≠ t` (row-major, `slots²`), its pair and half in the
    /// reduced system, if in the pattern.
    own_pairs: Vec<Option<(usize, usize)>>,
    /// With [`LinearSolver::keep_factors`]: per interior node (indexed like
    /// `interior_nodes`) its pivot's inverse `D'_k⁻¹` and the junction coupling `r` before its
    /// elimination, for [`LinearSolver::solve_again`]; empty otherwise.
    kept: Vec<[Block<D>; 2]>,
    /// Whether the last successful [`LinearSolver::solve`] found the junctions uncoupled (every
    /// segment's coupling blocks zero, no border): the reduced system was then solved block
    /// by block with the inverses of `jdiag`, not factored.
    apart: bool,
}

impl<const D: usize> std::fmt::Debug for NetworkSolver<D> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NetworkSolver")
            .field("junctions", &self.junctions.len())
            .field("segments", &self.segments.len())
            .field("interior", &self.interior_nodes.len())
            .finish_non_exhaustive()
    }
}

/// The junction/segment decomposition of a mesh's element graph.
struct Decomposition {
    is_junction: Vec<bool>,
    segments: Vec<Segment>,
    interior_nodes: Vec<usize>,
    path_elements: Vec<(usize, bool)>,
}

/// The decomposition of `mesh` with the nodes `forced` (and the default ones) junctions.
fn decompose(mesh: &Mesh, forced: &[usize]) -> Decomposition {
    let n = mesh.n_nodes();
    let els = mesh.elements();
    // Incidence lists in CSR form: elements of node v are inc[start[v]..start[v + 1]].
    let mut start = vec![0usize; n + 1];
    for &[a, b] in els {
        start[a + 1] += 1;
        start[b + 1] += 1;
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut inc = vec![0usize; 2 * els.len()];
    for (e, &[a, b]) in els.iter().enumerate() {
        for v in [a, b] {
            inc[fill[v]] = e;
            fill[v] += 1;
        }
    }
    let other = |e: usize, v: usize| if els[e][0] == v { els[e][1] } else { els[e][0] };
    let mut is_junction: Vec<bool> = (0..n)
        .map(|v| {
            let i = &inc[start[v]..start[v + 1]];
            !(i.len() == 2 && other(i[0], v) != other(i[1], v))
        })
        .collect();
    for &v in forced {
        is_junction[v] = true;
    }
    let mut d = Decomposition {
        is_junction: Vec::new(),
        segments: Vec::new(),
        interior_nodes: Vec::new(),
        path_elements: Vec::new(),
    };
    let mut visited = vec![false; els.len()];
    // Walks from junction `j` along element `e0` to the next junction, recording a segment.
    let trace =
        |d: &mut Decomposition, visited: &mut [bool], is_junction: &[bool], j: usize, e0: usize| {
            let first_interior = d.interior_nodes.len();
            let first_element = d.path_elements.len();
            visited[e0] = true;
            d.path_elements.push((e0, els[e0][0] == j));
            let (mut prev, mut cur) = (e0, other(e0, j));
            while !is_junction[cur] {
                d.interior_nodes.push(cur);
                let i = &inc[start[cur]..start[cur] + 2];
                let e = if i[0] == prev { i[1] } else { i[0] };
                visited[e] = true;
                d.path_elements.push((e, els[e][0] == cur));
                prev = e;
                cur = other(e, cur);
            }
            d.segments.push(Segment {
                ends: [j, cur],
                first_interior,
                n_interior: d.interior_nodes.len() - first_interior,
                first_element,
                coupling: NOT_A_JUNCTION,
            });
        };
    for j in 0..n {
        if is_junction[j] {
            for &e in &inc[start[j]..start[j + 1]] {
                if !visited[e] {
                    trace(&mut d, &mut visited, &is_junction, j, e);
                }
            }
        }
    }
    // What is left are rings of interior nodes: declare one node of each a junction.
    for e in 0..els.len() {
        if !visited[e] {
            let j = els[e][0];
            is_junction[j] = true;
            trace(&mut d, &mut visited, &is_junction, j, e);
        }
    }
    d.is_junction = is_junction;
    d
}

/// Appends the border's pairs to the reduced system's `pairs` (junction rows `0..nj` by
/// `junction_index`, slot `s` at row `nj + s`): one per distinct `[node, slot]` link, then one
/// per distinct slot pair. Returns the links' pairs (sorted by `[node, slot]`) and, per slot
/// block `(s, t)` (row-major), its pair and half.
#[allow(clippy::type_complexity)]
fn border_pairs(
    border: &BorderPattern,
    junction_index: &[usize],
    pairs: &mut Vec<[usize; 2]>,
) -> (Vec<([usize; 2], usize)>, Vec<Option<(usize, usize)>>) {
    let m = border.slots;
    let nj = junction_index
        .iter()
        .filter(|&&r| r != NOT_A_JUNCTION)
        .count();
    let mut links = border.links.clone();
    links.sort_unstable();
    links.dedup();
    let link_pairs = links
        .into_iter()
        .map(|[node, slot]| {
            pairs.push([junction_index[node], nj + slot]);
            ([node, slot], pairs.len() - 1)
        })
        .collect();
    let mut own: Vec<[usize; 2]> = border
        .pairs
        .iter()
        .filter(|[s, t]| s != t)
        .map(|&[s, t]| [s.min(t), s.max(t)])
        .collect();
    own.sort_unstable();
    own.dedup();
    let mut own_pairs = vec![None; m * m];
    for [s, t] in own {
        pairs.push([nj + s, nj + t]);
        own_pairs[s * m + t] = Some((pairs.len() - 1, 0));
        own_pairs[t * m + s] = Some((pairs.len() - 1, 1));
    }
    (link_pairs, own_pairs)
}

impl<const D: usize> NetworkSolver<D> {
    /// Decomposes `mesh` into junctions and segments and analyses the sparsity pattern of
    /// the reduced junction system, factored by [`JunctionLu::Block`] (no allocation per
    /// solve).
    pub fn new(mesh: &Mesh) -> Self {
        Self::with_junction_lu(mesh, JunctionLu::Block)
    }

    /// As [`NetworkSolver::new`], with the factorization `junction_lu` of the reduced
    /// junction system.
    pub fn with_junction_lu(mesh: &Mesh, junction_lu: JunctionLu) -> Self {
        Self::build(mesh, &BorderPattern::default(), junction_lu)
    }

    /// The solver of the Newton matrix of `mesh` bordered by the slots of `border` (unknowns
    /// after the nodes, two per rigid body): the slots are rows of the reduced system, the
    /// nodes they couple with junctions. An index of `border` out of range is an error.
    pub fn with_border(
        mesh: &Mesh,
        border: &BorderPattern,
        junction_lu: JunctionLu,
    ) -> Result<Self, SetupError> {
        let (n, m) = (mesh.n_nodes(), border.slots);
        for &[node, slot] in &border.links {
            if node >= n {
                return Err(SetupError::NodeOutOfRange {
                    what: "a link of the linear solver's border",
                    node,
                    n_nodes: n,
                });
            }
            if slot >= m {
                return Err(SetupError::SlotOutOfRange {
                    what: "a link of the linear solver's border",
                    slot,
                    slots: m,
                });
            }
        }
        if let Some(&slot) = border.pairs.iter().flatten().find(|&&s| s >= m) {
            return Err(SetupError::SlotOutOfRange {
                what: "a slot pair of the linear solver's border",
                slot,
                slots: m,
            });
        }
        Ok(Self::build(mesh, border, junction_lu))
    }

    /// [`NetworkSolver::with_border`] for a `border` whose indices are in range.
    fn build(mesh: &Mesh, border: &BorderPattern, junction_lu: JunctionLu) -> Self {
        let (n, m) = (mesh.n_nodes(), border.slots);
        let forced: Vec<usize> = border.links.iter().map(|&[node, _]| node).collect();
        let mut dec = decompose(mesh, &forced);
        let junctions: Vec<usize> = (0..n).filter(|&v| dec.is_junction[v]).collect();
        let mut junction_index = vec![NOT_A_JUNCTION; n];
        for (r, &j) in junctions.iter().enumerate() {
            junction_index[j] = r;
        }
        let nj = junctions.len();
        // Coupling pairs (start, end) of the non-loop segments, in junction indices.
        let mut pairs = Vec::new();
        for s in &mut dec.segments {
            let [a, b] = s.ends.map(|v| junction_index[v]);
            if a != b {
                s.coupling = pairs.len();
                pairs.push([a, b]);
            }
        }
        let (link_pairs, own_pairs) = border_pairs(border, &junction_index, &mut pairs);
        let n_red = nj + m;
        let reduced = (n_red > 0).then(|| match junction_lu {
            JunctionLu::Block => {
                let lu = BlockLu::new(n_red, &pairs);
                let slots = pairs
                    .iter()
                    .map(|&[a, b]| [lu.slot(a, b), lu.slot(b, a)])
                    .collect();
                Reduced::Block { lu, slots }
            }
            JunctionLu::Simplicial => Reduced::Faer(FaerReduced::new::<D>(n_red, &pairs)),
        });
        let n_int = dec.interior_nodes.len();
        Self {
            rows: junctions.iter().copied().chain(n..n + m).collect(),
            junctions,
            junction_index,
            segments: dec.segments,
            interior_nodes: dec.interior_nodes,
            path_elements: dec.path_elements,
            cg: vec![[Block::zeros(); 2]; n_int],
            jdiag: vec![Block::zeros(); nj],
            reduced,
            n_nodes: n,
            n_slots: m,
            link_pairs,
            own_pairs,
            kept: Vec::new(),
            apart: false,
        }
    }

    /// Number of junction nodes (the size of the reduced system, in blocks).
    pub fn n_junctions(&self) -> usize {
        self.junctions.len()
    }
    /// Number of segments (paths junction – interior – … – junction).
    pub fn n_segments(&self) -> usize {
        self.segments.len()
    }
    /// Number of interior nodes, eliminated by block Thomas along the segments.
    pub fn n_interior(&self) -> usize {
        self.interior_nodes.len()
    }
    /// Whether node `v` is a junction (solved in the reduced system).
    pub fn is_junction(&self, v: usize) -> bool {
        self.junction_index[v] != NOT_A_JUNCTION
    }

    /// Blocks `[F, B]` of path element `p`: `F = ∂R_from/∂x_to`, `B = ∂R_to/∂x_from`.
    #[inline]
    fn path_blocks<'a>(&self, jac: &'a BlockJacobian<D>, p: usize) -> [&'a Block<D>; 2] {
        let (e, forward) = self.path_elements[p];
        let off = &jac.off[e];
        if forward {
            [&off[0], &off[1]]
        } else {
            [&off[1], &off[0]]
        }
    }

    /// Eliminates the interior nodes of segment `s` in path order (one front from the start
    /// junction; the nodes of a string are numbered consecutively in most meshes, and memory
    /// is then read as one stream): stores `C_k`, `G_k` and `y_k` (in `rhs`), adds the Schur
    /// complement to `jdiag`, `rhs` of the end junctions and returns the coupling blocks
    /// `[(start, end), (end, start)]` (`None` for a loop, whose couplings go to `jdiag`).
    fn eliminate(
        &mut self,
        s: usize,
        jac: &BlockJacobian<D>,
        rhs: &mut [SVector<f64, D>],
    ) -> Result<Option<[Block<D>; 2]>, LinearSolveError> {
        let seg = self.segments[s];
        let [j0, j1] = seg.ends;
        let e0 = seg.first_element;
        let [f, b] = self.path_blocks(jac, e0);
        let mut front = Front::new(f, b);
        for k in 1..=seg.n_interior {
            // Interior node k (node 0 is j0); element e0 + k leads to node k + 1.
            let q = seg.first_interior + k - 1;
            let node = self.interior_nodes[q];
            let [fo, bo] = self.path_blocks(jac, e0 + k);
            let r_before = front.r;
            let (cg, inv) = front
                .step(&jac.diag[node], &mut rhs[node], fo, bo)
                .ok_or(LinearSolveError::Singular { block: node })?;
            self.cg[q] = cg;
            if let Some(kept) = self.kept.get_mut(q) {
                *kept = [inv, r_before];
            }
        }
        let (r0, r1) = (self.junction_index[j0], self.junction_index[j1]);
        self.jdiag[r0] += front.acc_d;
        rhs[j0] += front.acc_b;
        if let Some((bp, cp, yp)) = &front.prev {
            self.jdiag[r1] -= bp * cp;
            rhs[j1] -= bp * yp;
        }
        Ok(self.couple(seg, [front.r, front.l]))
    }

    /// The coupling blocks `[(start, end), (end, start)]` of segment `seg`, or `None` after
    /// adding them to the diagonal block of a loop.
    fn couple(&mut self, seg: Segment, couplings: [Block<D>; 2]) -> Option<[Block<D>; 2]> {
        if seg.coupling == NOT_A_JUNCTION {
            self.jdiag[self.junction_index[seg.ends[0]]] += couplings[0] + couplings[1];
            None
        } else {
            Some(couplings)
        }
    }

    /// Back substitution along segment `seg` once its end junctions are solved:
    /// `x_k = y_k − C_k x_{k+1} − G_k x_{j0}` from the end junction backwards.
    fn back_substitute(
        &self,
        seg: &Segment,
        rhs: &mut [SVector<f64, D>],
    ) -> Result<(), LinearSolveError> {
        let [j0, j1] = seg.ends;
        let x0 = rhs[j0];
        let mut next = rhs[j1];
        let range = seg.first_interior..seg.first_interior + seg.n_interior;
        for (&node, [c, g]) in self.interior_nodes[range.clone()]
            .iter()
            .zip(&self.cg[range])
            .rev()
        {
            let x = rhs[node] - c * next - g * x0;
            if !finite(&x) {
                return Err(LinearSolveError::Singular { block: node });
            }
            rhs[node] = x;
            next = x;
        }
        Ok(())
    }
}

/// One elimination front along a segment, moving away from its junction `J`.
struct Front<const D: usize> {
    /// Coupling of `J`'s row to the current node.
    r: Block<D>,
    /// Coupling of the current node's row to `J`.
    l: Block<D>,
    /// Schur-complement contributions to `J`'s diagonal block and right-hand side.
    acc_d: Block<D>,
    acc_b: SVector<f64, D>,
    /// `(B, C, y)` of the previously eliminated node: `B` its coupling into the current
    /// row.
    prev: Option<(Block<D>, Block<D>, SVector<f64, D>)>,
    /// Whether `J` couples to the segment at all: not when the element's blocks at `J` are
    /// zero (a support's row and column), and then `r`, `l` and the `G_k` stay zero.
    coupled: bool,
}

impl<const D: usize> Front<D> {
    /// A front starting at the node next to `J`, with the blocks `[F, B]` of the element
    /// from `J` to it.
    fn new(f: &Block<D>, b: &Block<D>) -> Self {
        Self {
            r: *f,
            l: *b,
            acc_d: Block::zeros(),
            acc_b: SVector::zeros(),
            prev: None,
            coupled: f.iter().chain(b.iter()).any(|&v| v != 0.0),
        }
    }

    /// Eliminates the current node (diagonal block `d`, right-hand side `b`, overwritten by
    /// `y`), whose element to the next node has the blocks `[fo, bo]`; returns `[C, G]`,
    /// or `None` for a singular pivot.
    #[inline(always)]
    fn step(
        &mut self,
        d: &Block<D>,
        b: &mut SVector<f64, D>,
        fo: &Block<D>,
        bo: &Block<D>,
    ) -> Option<([Block<D>; 2], Block<D>)> {
        let mut d = *d;
        if let Some((bp, cp, yp)) = &self.prev {
            d -= bp * cp;
            *b -= bp * yp;
        }
        let inv = d.try_inverse()?;
        let y = inv * *b;
        let c = inv * fo;
        *b = y;
        let g = if self.coupled {
            let g = inv * self.l;
            self.acc_d -= self.r * g;
            self.acc_b -= self.r * y;
            self.r = -(self.r * c);
            self.l = -(bo * g);
            g
        } else {
            Block::zeros()
        };
        self.prev = Some((*bo, c, y));
        Some(([c, g], inv))
    }
}

/// Solves the reduced system of uncoupled `junctions` in place: each junction's unknowns by
/// the inverse of its Schur-complemented diagonal block (`jdiag`, indexed like `junctions`).
fn solve_apart<const D: usize>(
    junctions: &[usize],
    jdiag: &[Block<D>],
    rhs: &mut [SVector<f64, D>],
) -> Result<(), LinearSolveError> {
    for (blk, &j) in jdiag.iter().zip(junctions) {
        let inv = blk
            .try_inverse()
            .ok_or(LinearSolveError::Singular { block: j })?;
        rhs[j] = inv * rhs[j];
    }
    Ok(())
}

/// Whether all entries of `x` are finite.
fn finite<const D: usize>(x: &SVector<f64, D>) -> bool {
    x.iter().all(|v| v.is_finite())
}

impl<const D: usize> LinearSolver<D> for NetworkSolver<D> {
    fn solve(
        &mut self,
        jac: &BlockJacobian<D>,
        rhs: &mut [SVector<f64, D>],
    ) -> Result<(), LinearSolveError> {
        self.check_unknowns(jac, rhs)?;
        // The reduced system is moved out while the segments write into it.
        let mut reduced = self.reduced.take();
        let result = self.solve_with(&mut reduced, jac, rhs);
        self.reduced = reduced;
        result
    }
    fn name(&self) -> &'static str {
        "network"
    }
    fn keep_factors(&mut self) {
        self.kept = vec![[Block::zeros(); 2]; self.interior_nodes.len()];
    }
    fn solve_again(
        &mut self,
        jac: &BlockJacobian<D>,
        rhs: &mut [SVector<f64, D>],
    ) -> Result<(), LinearSolveError> {
        self.check_unknowns(jac, rhs)?;
        let kept_all = self.kept.len() == self.interior_nodes.len();
        let Some(Reduced::Block { lu, .. }) = self.reduced.as_mut().filter(|_| kept_all) else {
            return self.solve(jac, rhs);
        };
        // The right-hand side's part of each segment's elimination, with the kept pivots.
        for seg in &self.segments {
            let [j0, j1] = seg.ends;
            let mut acc_b = SVector::<f64, D>::zeros();
            let mut prev: Option<(usize, SVector<f64, D>)> = None;
            for k in 0..seg.n_interior {
                let q = seg.first_interior + k;
                let node = self.interior_nodes[q];
                let mut b = rhs[node];
                if let Some((p, yp)) = prev {
                    // The coupling of this node's row to the previous one: `B` of element
                    // e0 + k (the block `∂R_to/∂x_from` along the path).
                    let (e, forward) = self.path_elements[p];
                    let bo = if forward {
                        &jac.off[e][1]
                    } else {
                        &jac.off[e][0]
                    };
                    b -= bo * yp;
                }
                let [inv, r] = &self.kept[q];
                let y = inv * b;
                acc_b -= r * y;
                rhs[node] = y;
                prev = Some((seg.first_element + k + 1, y));
            }
            rhs[j0] += acc_b;
            if let Some((p, yp)) = prev {
                let (e, forward) = self.path_elements[p];
                let bo = if forward {
                    &jac.off[e][1]
                } else {
                    &jac.off[e][0]
                };
                rhs[j1] -= bo * yp;
            }
        }
        if self.apart {
            solve_apart(&self.junctions, &self.jdiag, rhs)?;
        } else {
            lu.solve_indexed(rhs, &self.rows);
        }
        for &j in &self.rows {
            if !finite(&rhs[j]) {
                return Err(LinearSolveError::Singular { block: j });
            }
        }
        for seg in self.segments.iter().rev() {
            self.back_substitute(seg, rhs)?;
        }
        Ok(())
    }
}

impl<const D: usize> NetworkSolver<D> {
    /// Adds the border's blocks of `jac` to the reduced system: the slots' own blocks and
    /// their links with the (junction) nodes. A nonzero block outside the pattern is an
    /// error.
    fn add_border(
        &self,
        red: &mut Reduced<D>,
        jac: &BlockJacobian<D>,
    ) -> Result<(), LinearSolveError> {
        let (n, m, nj) = (self.n_nodes, self.n_slots, self.junctions.len());
        if m == 0 {
            return Ok(());
        }
        for (st, (blk, pair)) in jac.border.own.iter().zip(&self.own_pairs).enumerate() {
            let (s, t) = (st / m, st % m);
            match pair {
                _ if s == t => red.add_diag(nj + s, blk),
                Some((p, half)) => red.add_half(*p, *half, blk),
                None if blk.iter().any(|&v| v != 0.0) => {
                    return Err(LinearSolveError::OutsidePattern {
                        row: n + s,
                        col: n + t,
                    });
                }
                None => {}
            }
        }
        for (node, slot, row, col) in &jac.border.links {
            let key = [*node, *slot];
            let at = self
                .link_pairs
                .binary_search_by_key(&key, |&(k, _)| k)
                .map_err(|_| LinearSolveError::OutsidePattern {
                    row: n + slot,
                    col: *node,
                })?;
            // Pair `[node, slot]`: block (node, slot) is ∂R_node/∂u_slot, (slot, node) the row.
            red.add_coupling(self.link_pairs[at].1, &[*col, *row]);
        }
        Ok(())
    }

    /// `Err` unless `jac` has the nodes and slots the solver was built for and `rhs` at
    /// least as many entries (without slots, `jac`'s border is not read).
    fn check_unknowns(
        &self,
        jac: &BlockJacobian<D>,
        rhs: &[SVector<f64, D>],
    ) -> Result<(), LinearSolveError> {
        let (n, m) = (self.n_nodes, self.n_slots);
        let slots = if m == 0 { 0 } else { jac.border.slots };
        let found = if jac.diag.len() == n && slots == m {
            rhs.len().min(n + m)
        } else {
            jac.diag.len() + slots
        };
        if found == n + m {
            Ok(())
        } else {
            Err(LinearSolveError::Unknowns {
                expected: n + m,
                found,
            })
        }
    }

    fn solve_with(
        &mut self,
        reduced: &mut Option<Reduced<D>>,
        jac: &BlockJacobian<D>,
        rhs: &mut [SVector<f64, D>],
    ) -> Result<(), LinearSolveError> {
        let Some(red) = reduced else {
            // No junctions means no elements: the matrix is block diagonal.
            for (i, (x, d)) in rhs.iter_mut().zip(&jac.diag).enumerate() {
                let inv = d
                    .try_inverse()
                    .ok_or(LinearSolveError::Singular { block: i })?;
                *x = inv * *x;
                if !finite(x) {
                    return Err(LinearSolveError::Singular { block: i });
                }
            }
            return Ok(());
        };
        for (r, &j) in self.junctions.iter().enumerate() {
            self.jdiag[r] = jac.diag[j];
        }
        // The reduced system is cleared at the first nonzero coupling: when every segment's
        // couplings are zero (an end junction of each is a support fixed in every direction,
        // whose rows and columns are the identity's) and there is no border, it is block
        // diagonal and solved so.
        let mut coupled = self.n_slots > 0;
        if coupled {
            red.clear();
        }
        for s in 0..self.segments.len() {
            if let Some(blocks) = self.eliminate(s, jac, rhs)? {
                if !coupled {
                    if blocks.iter().all(|b| b.iter().all(|&v| v == 0.0)) {
                        continue;
                    }
                    red.clear();
                    coupled = true;
                }
                red.add_coupling(self.segments[s].coupling, &blocks);
            }
        }
        self.apart = !coupled;
        if self.apart {
            solve_apart(&self.junctions, &self.jdiag, rhs)?;
        } else {
            for (r, blk) in self.jdiag.iter().enumerate() {
                red.add_diag(r, blk);
            }
            self.add_border(red, jac)?;
            match red {
                Reduced::Block { lu, .. } => {
                    lu.factor().map_err(|r| LinearSolveError::Singular {
                        block: self.rows[r],
                    })?;
                    lu.solve_indexed(rhs, &self.rows);
                }
                Reduced::Faer(red) => {
                    for (r, &j) in self.rows.iter().enumerate() {
                        red.lu.rhs[r * D..(r + 1) * D].copy_from_slice(rhs[j].as_slice());
                    }
                    red.lu.factor_and_solve()?;
                    for (r, &j) in self.rows.iter().enumerate() {
                        rhs[j].copy_from_slice(&red.lu.rhs[r * D..(r + 1) * D]);
                    }
                }
            }
        }
        for &j in &self.rows {
            if !finite(&rhs[j]) {
                return Err(LinearSolveError::Singular { block: j });
            }
        }
        // Segments last to first, each backwards: `cg` (and the interior nodes of strings
        // numbered consecutively) are read as one descending stream, which the prefetcher
        // follows (forwards segment by segment, 1.2 ms slower on the benchmark net).
        for seg in self.segments.iter().rev() {
            self.back_substitute(seg, rhs)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::DMatrix;

    use super::*;
    use crate::linsolve::{SolverKind, SparseLu, make_solver};
    use crate::testing::grid_net;

    use crate::linsolve::test_rng::Rng;

    fn mesh(n_nodes: usize, elements: Vec<[usize; 2]>) -> Mesh {
        let n = elements.len();
        Mesh::new(n_nodes, elements, vec![1.0; n]).unwrap()
    }

    fn chain(n_el: usize) -> Mesh {
        Mesh::uniform_chain(n_el, 1.0).unwrap()
    }

    /// `arms` chains of `len` elements joined at node 0.
    fn star(arms: usize, len: usize) -> Mesh {
        let mut els = Vec::new();
        let mut next = 1;
        for _ in 0..arms {
            let mut prev = 0;
            for _ in 0..len {
                els.push([prev, next]);
                prev = next;
                next += 1;
            }
        }
        mesh(next, els)
    }

    fn ring(n: usize) -> Mesh {
        mesh(n, (0..n).map(|i| [i, (i + 1) % n]).collect())
    }

    /// Two chains of 20 elements (nodes 0–20 and 21–41), a second element parallel to
    /// `[5, 6]`, a spring between interior nodes 12 and 30, and an isolated node 42.
    fn parallel_and_spring() -> Mesh {
        let mut els: Vec<[usize; 2]> = (0..20).map(|i| [i, i + 1]).collect();
        els.extend((21..41).map(|i| [i, i + 1]));
        els.push([6, 5]);
        els.push([12, 30]);
        mesh(43, els)
    }

    /// A chain of 10 elements whose last node carries a loop of 8 elements back to itself.
    fn lollipop() -> Mesh {
        let mut els: Vec<[usize; 2]> = (0..10).map(|i| [i, i + 1]).collect();
        let ring: Vec<usize> = std::iter::once(10).chain(11..18).collect();
        for k in 0..ring.len() {
            els.push([ring[k], ring[(k + 1) % ring.len()]]);
        }
        mesh(18, els)
    }

    /// `mesh` with its nodes renumbered by a random permutation, its elements reordered and
    /// randomly flipped; returns the permutation (old node → new node) too.
    fn shuffled(mesh: &Mesh, rng: &mut Rng) -> (Mesh, Vec<usize>) {
        let n = mesh.n_nodes();
        let mut perm: Vec<usize> = (0..n).collect();
        for i in (1..n).rev() {
            perm.swap(i, rng.below(i + 1));
        }
        let mut els: Vec<[usize; 2]> = mesh
            .elements()
            .iter()
            .map(|&[a, b]| {
                if rng.below(2) == 0 {
                    [perm[a], perm[b]]
                } else {
                    [perm[b], perm[a]]
                }
            })
            .collect();
        for i in (1..els.len()).rev() {
            els.swap(i, rng.below(i + 1));
        }
        (self::mesh(n, els), perm)
    }

    /// Mass-dominated random Newton matrix: `diag = big·I + random`, off blocks random and
    /// not symmetric.
    fn random_jac<const D: usize>(mesh: &Mesh, rng: &mut Rng) -> BlockJacobian<D> {
        let mut jac = BlockJacobian::<D>::zeros(mesh);
        let big = 8.0 * D as f64;
        for d in &mut jac.diag {
            *d = Block::from_fn(|_, _| rng.sym()) + Block::identity() * big;
        }
        for off in &mut jac.off {
            for b in off.iter_mut() {
                *b = Block::from_fn(|_, _| rng.sym());
            }
        }
        jac
    }

    fn random_rhs<const D: usize>(n: usize, rng: &mut Rng) -> Vec<SVector<f64, D>> {
        (0..n).map(|_| SVector::from_fn(|_, _| rng.sym())).collect()
    }

    fn dense<const D: usize>(mesh: &Mesh, jac: &BlockJacobian<D>) -> DMatrix<f64> {
        let n = mesh.n_nodes() * D;
        let mut m = DMatrix::zeros(n, n);
        let mut add = |i: usize, j: usize, b: &Block<D>| {
            for k in 0..D {
                for l in 0..D {
                    m[(i * D + k, j * D + l)] += b[(k, l)];
                }
            }
        };
        for (i, d) in jac.diag.iter().enumerate() {
            add(i, i, d);
        }
        for (&[a, b], off) in mesh.elements().iter().zip(&jac.off) {
            add(a, b, &off[0]);
            add(b, a, &off[1]);
        }
        m
    }

    fn flat<const D: usize>(x: &[SVector<f64, D>]) -> nalgebra::DVector<f64> {
        nalgebra::DVector::from_iterator(x.len() * D, x.iter().flat_map(|v| v.iter().copied()))
    }

    /// Solves three random systems on `mesh` (one solver, refactored each time) with the
    /// network solver (all junction LU variants) and the sparse LU oracle; checks agreement
    /// and the dense residual.
    fn check<const D: usize>(mesh: &Mesh, seed: u64) {
        let mut rng = Rng(seed);
        let mut nets = [JunctionLu::Block, JunctionLu::Simplicial]
            .map(|k| NetworkSolver::<D>::with_junction_lu(mesh, k));
        let mut lu = SparseLu::<D>::new(mesh);
        for _ in 0..3 {
            let jac = random_jac::<D>(mesh, &mut rng);
            let b = random_rhs::<D>(mesh.n_nodes(), &mut rng);
            let mut x_lu = b.clone();
            lu.solve(&jac, &mut x_lu).unwrap();
            let (x_lu, bf) = (flat(&x_lu), flat(&b));
            let j = dense(mesh, &jac);
            for net in &mut nets {
                let mut x = b.clone();
                net.solve(&jac, &mut x).unwrap();
                let x = flat(&x);
                let diff = (&x - &x_lu).norm() / x_lu.norm();
                assert!(diff <= 1e-10, "D = {D}: network vs sparse LU {diff:e}");
                let res = (&j * &x - &bf).norm() / bf.norm();
                assert!(res <= 1e-10, "D = {D}: residual {res:e}");
            }
            check_again::<D>(mesh, &jac, &mut rng);
        }
    }

    /// A second right-hand side solved with the kept factors of the first solve
    /// (`solve_again`, used by the bordered solve) agrees with the sparse LU: the network
    /// solver and, on a chain, the block-tridiagonal one.
    fn check_again<const D: usize>(mesh: &Mesh, jac: &BlockJacobian<D>, rng: &mut Rng) {
        let mut solvers: Vec<Box<dyn LinearSolver<D>>> = vec![Box::new(NetworkSolver::new(mesh))];
        if mesh.is_chain() {
            solvers.push(Box::new(
                crate::linsolve::BlockTridiagonal::new(mesh).unwrap(),
            ));
        }
        let mut lu = SparseLu::<D>::new(mesh);
        let (b1, b2) = (
            random_rhs::<D>(mesh.n_nodes(), rng),
            random_rhs::<D>(mesh.n_nodes(), rng),
        );
        let mut x_lu = b2.clone();
        lu.solve(jac, &mut x_lu).unwrap();
        let x_lu = flat(&x_lu);
        for solver in &mut solvers {
            solver.keep_factors();
            let mut x1 = b1.clone();
            solver.solve(jac, &mut x1).unwrap();
            let mut x2 = b2.clone();
            solver.solve_again(jac, &mut x2).unwrap();
            let diff = (&flat(&x2) - &x_lu).norm() / x_lu.norm();
            assert!(
                diff <= 1e-10,
                "D = {D}: {} solve_again vs sparse LU {diff:e}",
                solver.name()
            );
        }
    }

    fn check_all_d(mesh: &Mesh, seed: u64) {
        check::<1>(mesh, seed);
        check::<2>(mesh, seed + 1);
        check::<3>(mesh, seed + 2);
    }

    /// Checks `mesh` and a shuffled copy, and that the shuffled copy decomposes into the
    /// same junctions (mapped by the permutation), segments and interior nodes.
    fn check_with_shuffle(mesh: &Mesh, seed: u64) {
        check_all_d(mesh, seed);
        let mut rng = Rng(seed ^ 0xABCD);
        let (sh, perm) = shuffled(mesh, &mut rng);
        check_all_d(&sh, seed + 10);
        let a = NetworkSolver::<1>::new(mesh);
        let b = NetworkSolver::<1>::new(&sh);
        assert_eq!(a.n_segments(), b.n_segments());
        assert_eq!(a.n_junctions(), b.n_junctions());
        assert_eq!(a.n_interior(), b.n_interior());
        for (v, &pv) in perm.iter().enumerate() {
            assert_eq!(a.is_junction(v), b.is_junction(pv), "node {v}");
        }
    }

    #[test]
    fn chain_is_one_segment_and_matches_sparse_lu() {
        let m = chain(40);
        let s = NetworkSolver::<2>::new(&m);
        assert_eq!(
            (s.n_junctions(), s.n_segments(), s.n_interior()),
            (2, 1, 39)
        );
        check_with_shuffle(&m, 1);
        check_all_d(&chain(1), 2);
        check_all_d(&chain(2), 3);
    }

    #[test]
    fn star_of_three_chains_matches_sparse_lu() {
        let m = star(3, 15);
        let s = NetworkSolver::<2>::new(&m);
        // The centre and the three free ends.
        assert_eq!(
            (s.n_junctions(), s.n_segments(), s.n_interior()),
            (4, 3, 42)
        );
        check_with_shuffle(&m, 20);
    }

    #[test]
    fn ring_gets_one_junction_and_matches_sparse_lu() {
        for n in [3, 4, 17] {
            let m = ring(n);
            let s = NetworkSolver::<2>::new(&m);
            assert_eq!(
                (s.n_junctions(), s.n_segments(), s.n_interior()),
                (1, 1, n - 1)
            );
            check_all_d(&m, 30 + n as u64);
            let (sh, _) = shuffled(&m, &mut Rng(n as u64));
            check_all_d(&sh, 40 + n as u64);
        }
        // Two nodes joined by two parallel elements: both are junctions.
        let m = mesh(2, vec![[0, 1], [1, 0]]);
        let s = NetworkSolver::<2>::new(&m);
        assert_eq!((s.n_junctions(), s.n_segments(), s.n_interior()), (2, 2, 0));
        check_all_d(&m, 50);
    }

    #[test]
    fn loop_segment_through_interior_nodes_matches_sparse_lu() {
        let m = lollipop();
        let s = NetworkSolver::<2>::new(&m);
        // Ends 0 and 10; the loop 10 → 11 … 17 → 10 is one segment with both ends at 10.
        assert_eq!(
            (s.n_junctions(), s.n_segments(), s.n_interior()),
            (2, 2, 16)
        );
        check_with_shuffle(&m, 60);
    }

    #[test]
    fn square_net_of_crossing_strings_matches_sparse_lu() {
        let m = grid_net(6, 6, 5, 2);
        let s = NetworkSolver::<2>::new(&m);
        // 36 crossings and 24 free ends; per string 5 inner segments and 2 tails.
        assert_eq!(s.n_junctions(), 36 + 24);
        assert_eq!(s.n_segments(), 12 * 7);
        assert_eq!(s.n_junctions() + s.n_interior(), m.n_nodes());
        check_with_shuffle(&m, 70);
        // Crossings one element apart: segments without interior nodes.
        check_with_shuffle(&grid_net(4, 3, 1, 1), 80);
    }

    /// `lines` strings of `segs` elements between supports, numbered as a MoorDyn deck's
    /// network is: the end points first (anchors `0..lines`, then the fairleads), then each
    /// line's interior nodes.
    fn moored(lines: usize, segs: usize) -> Mesh {
        let mut els = Vec::new();
        let mut next = 2 * lines;
        for l in 0..lines {
            let mut prev = l;
            for _ in 0..segs - 1 {
                els.push([prev, next]);
                prev = next;
                next += 1;
            }
            els.push([prev, lines + l]);
        }
        mesh(next, els)
    }

    /// `jac` with the rows and columns of the nodes `held` those of the identity, as the
    /// masking of a support leaves them.
    fn hold<const D: usize>(mesh: &Mesh, jac: &mut BlockJacobian<D>, held: &[usize]) {
        for &i in held {
            jac.diag[i] = Block::identity();
        }
        for (&[a, b], off) in mesh.elements().iter().zip(&mut jac.off) {
            if held.contains(&a) || held.contains(&b) {
                *off = [Block::zeros(); 2];
            }
        }
    }

    /// Three lines between supports: the junctions are solved apart (no junction LU); with
    /// one fairlead free, or all three, still apart (the free junctions' Schur-complemented
    /// blocks are no longer the identity; a line's coupling is then zero from its end's
    /// blocks, not its start's); with both ends of the third line free the reduced system is
    /// cleared and factored after two uncoupled segments. One solver per junction LU goes
    /// through the cases in an order that switches between the two ways both ways, with a
    /// reduced system left from a factored solve. Each solve and `solve_again` agrees with
    /// the sparse LU.
    #[test]
    fn lines_between_supports_solve_their_junctions_apart_and_match_sparse_lu() {
        let m = moored(3, 20);
        let mut rng = Rng(0x5EA);
        let cases: [(&[usize], bool); 6] = [
            (&[0, 1, 3, 4], false),
            (&[0, 1, 2, 3, 4, 5], true),
            (&[0, 1, 2, 3, 4], true),
            (&[0, 1, 3, 4], false),
            (&[0, 1, 2], true),
            (&[3, 4, 5], true),
        ];
        for kind in [JunctionLu::Block, JunctionLu::Simplicial] {
            let mut net = NetworkSolver::<3>::with_junction_lu(&m, kind);
            net.keep_factors();
            let mut lu = SparseLu::<3>::new(&m);
            for (held, apart) in cases {
                let mut jac = random_jac::<3>(&m, &mut rng);
                hold(&m, &mut jac, held);
                let (b1, b2) = (
                    random_rhs::<3>(m.n_nodes(), &mut rng),
                    random_rhs::<3>(m.n_nodes(), &mut rng),
                );
                for (b, again) in [(&b1, false), (&b2, true)] {
                    let mut x_lu = b.clone();
                    lu.solve(&jac, &mut x_lu).unwrap();
                    let mut x = b.clone();
                    if again {
                        net.solve_again(&jac, &mut x).unwrap();
                    } else {
                        net.solve(&jac, &mut x).unwrap();
                    }
                    let x_lu = flat(&x_lu);
                    let diff = (&flat(&x) - &x_lu).norm() / x_lu.norm();
                    assert!(diff <= 1e-10, "held {held:?}, again {again}: {diff:e}");
                }
                assert_eq!(net.apart, apart, "held {held:?}");
            }
        }
    }

    #[test]
    fn parallel_element_spring_and_isolated_node_match_sparse_lu() {
        let m = parallel_and_spring();
        let s = NetworkSolver::<2>::new(&m);
        for v in [0, 5, 6, 12, 20, 21, 30, 41, 42] {
            assert!(s.is_junction(v), "node {v}");
        }
        assert_eq!(s.n_junctions(), 9);
        // Chain 1: 0–5, 5=6 (two), 6–12, 12–20; chain 2: 21–30, 30–41; the spring.
        assert_eq!(s.n_segments(), 8);
        check_with_shuffle(&m, 90);
    }

    #[test]
    fn singular_and_non_finite_are_reported() {
        let m = star(3, 4);
        let mut s = NetworkSolver::<2>::new(&m);
        // A zero row: interior node 2 of arm 1–4 (elements [1, 2] and [2, 3]), a zero pivot
        // whichever side it is eliminated from.
        let mut jac = random_jac::<2>(&m, &mut Rng(1));
        jac.diag[2] = Block::zeros();
        jac.off[1][1] = Block::zeros();
        jac.off[2][0] = Block::zeros();
        let mut x = vec![SVector::<f64, 2>::repeat(1.0); m.n_nodes()];
        assert_eq!(
            s.solve(&jac, &mut x),
            Err(LinearSolveError::Singular { block: 2 })
        );
        // A NaN on a junction shows up in the junction solution.
        let mut jac = random_jac::<2>(&m, &mut Rng(2));
        jac.diag[0][(0, 0)] = f64::NAN;
        let mut x = vec![SVector::<f64, 2>::repeat(1.0); m.n_nodes()];
        let err = s.solve(&jac, &mut x).unwrap_err();
        assert!(
            matches!(
                err,
                LinearSolveError::Singular { .. } | LinearSolveError::Sparse(_)
            ),
            "{err:?}"
        );
        // The solver recovers with good values.
        let jac = random_jac::<2>(&m, &mut Rng(3));
        let mut x = vec![SVector::<f64, 2>::repeat(1.0); m.n_nodes()];
        s.solve(&jac, &mut x).unwrap();
    }

    /// A border of `m` slots on `mesh`: links of slot pairs `[2b, 2b + 1]` with `nodes`
    /// (body `b` takes `nodes[b]`), the slots of a body paired, bodies 0 and 1 paired.
    fn border_on(nodes: &[&[usize]]) -> BorderPattern {
        let m = 2 * nodes.len();
        let mut pattern = BorderPattern {
            slots: m,
            ..Default::default()
        };
        for (b, ns) in nodes.iter().enumerate() {
            pattern.pairs.push([2 * b + 1, 2 * b]);
            for &v in ns.iter() {
                pattern
                    .links
                    .extend([[v, 2 * b], [v, 2 * b + 1], [v, 2 * b]]);
            }
        }
        if nodes.len() > 1 {
            pattern.pairs.extend([[0, 3], [1, 2]]);
        }
        pattern
    }

    /// `random_jac` with random border blocks on `pattern` (the slots' diagonal blocks
    /// dominant, as a body's mass), each link given in two parts that add.
    fn random_bordered<const D: usize>(
        mesh: &Mesh,
        pattern: &BorderPattern,
        rng: &mut Rng,
    ) -> BlockJacobian<D> {
        let mut jac = random_jac::<D>(mesh, rng);
        let m = pattern.slots;
        jac.border = super::super::Border {
            slots: m,
            own: vec![Block::zeros(); m * m],
            links: Vec::new(),
        };
        let big = 8.0 * D as f64;
        for s in 0..m {
            jac.border.own[s * m + s] = Block::from_fn(|_, _| rng.sym()) + Block::identity() * big;
        }
        for &[s, t] in &pattern.pairs {
            jac.border.own[s * m + t] = Block::from_fn(|_, _| rng.sym());
            jac.border.own[t * m + s] = Block::from_fn(|_, _| rng.sym());
        }
        for &[node, slot] in &pattern.links {
            let (row, col) = (
                Block::from_fn(|_, _| rng.sym()),
                Block::from_fn(|_, _| rng.sym()),
            );
            jac.border.links.push((node, slot, row * 0.5, col * 0.5));
            jac.border.links.push((node, slot, row * 0.5, col * 0.5));
        }
        jac
    }

    /// The dense matrix of a bordered `jac` (nodes, then slots).
    fn dense_bordered<const D: usize>(mesh: &Mesh, jac: &BlockJacobian<D>) -> DMatrix<f64> {
        let (n, m) = (mesh.n_nodes(), jac.border.slots);
        let mut full = DMatrix::zeros((n + m) * D, (n + m) * D);
        full.view_mut((0, 0), (n * D, n * D))
            .copy_from(&dense(mesh, jac));
        let mut add = |i: usize, j: usize, b: &Block<D>| {
            let mut v = full.view_mut((i * D, j * D), (D, D));
            v += b;
        };
        for s in 0..m {
            for t in 0..m {
                add(n + s, n + t, &jac.border.own[s * m + t]);
            }
        }
        for &(node, slot, row, col) in &jac.border.links {
            add(n + slot, node, &row);
            add(node, n + slot, &col);
        }
        full
    }

    /// The network solver with the border `pattern` on `mesh` (both junction LUs, and its
    /// `solve_again`) against a dense LU of the whole matrix and the bordered sparse LU.
    fn check_border<const D: usize>(mesh: &Mesh, pattern: &BorderPattern, seed: u64) {
        let mut rng = Rng(seed);
        let (n, m) = (mesh.n_nodes(), pattern.slots);
        let mut nets = [JunctionLu::Block, JunctionLu::Simplicial]
            .map(|k| NetworkSolver::<D>::with_border(mesh, pattern, k).unwrap());
        nets[0].keep_factors();
        let mut schur = crate::linsolve::Bordered::<D>::new(Box::new(SparseLu::new(mesh)), n, m);
        for _ in 0..3 {
            let jac = random_bordered::<D>(mesh, pattern, &mut rng);
            let full = dense_bordered(mesh, &jac);
            let lu = full.clone().lu();
            for again in [false, true] {
                let b = random_rhs::<D>(n + m, &mut rng);
                let bf = flat(&b);
                let x_dense = lu.solve(&bf).unwrap();
                let mut x_schur = b.clone();
                schur.solve(&jac, &mut x_schur).unwrap();
                let diff = (&flat(&x_schur) - &x_dense).norm() / x_dense.norm();
                assert!(
                    diff <= 1e-10,
                    "D = {D}: bordered sparse LU vs dense {diff:e}"
                );
                for (k, net) in nets.iter_mut().enumerate() {
                    let mut x = b.clone();
                    if again && k == 0 {
                        net.solve_again(&jac, &mut x).unwrap();
                    } else {
                        net.solve(&jac, &mut x).unwrap();
                    }
                    let x = flat(&x);
                    let diff = (&x - &x_dense).norm() / x_dense.norm();
                    assert!(
                        diff <= 1e-10,
                        "D = {D}, {k}, again {again}: vs dense {diff:e}"
                    );
                    let res = (&full * &x - &bf).norm() / bf.norm();
                    assert!(res <= 1e-10, "D = {D}: residual {res:e}");
                }
            }
        }
    }

    #[test]
    fn border_slots_join_the_reduced_system_and_match_a_dense_solve() {
        // A chain with a body at its end node's neighbour and one on an interior node.
        let m = chain(30);
        let p = border_on(&[&[29], &[12, 13]]);
        let s = NetworkSolver::<3>::with_border(&m, &p, JunctionLu::Block).unwrap();
        // Ends 0, 30 and the linked nodes 12, 13, 29: four segments.
        assert_eq!((s.n_junctions(), s.n_segments()), (5, 4));
        for v in [12, 13, 29] {
            assert!(s.is_junction(v), "node {v}");
        }
        for (mesh, p, seed) in [
            (m, p, 100),
            (star(3, 15), border_on(&[&[15, 30, 45]]), 110),
            (star(4, 6), border_on(&[&[0, 3], &[9], &[20]]), 120),
            (ring(12), border_on(&[&[4, 9]]), 130),
            (lollipop(), border_on(&[&[14], &[3]]), 140),
            (grid_net(4, 3, 3, 1), border_on(&[&[1, 7, 20]]), 150),
        ] {
            check_border::<1>(&mesh, &p, seed);
            check_border::<2>(&mesh, &p, seed + 1);
            check_border::<3>(&mesh, &p, seed + 2);
        }
    }

    #[test]
    fn border_outside_its_pattern_is_reported() {
        let m = star(3, 4);
        let n = m.n_nodes();
        let p = border_on(&[&[4], &[8]]);
        let mut s = NetworkSolver::<2>::with_border(&m, &p, JunctionLu::Block).unwrap();
        let mut rng = Rng(7);
        let rhs = random_rhs::<2>(n + 4, &mut rng);
        // Slot 0 with slot 2: not paired.
        let mut jac = random_bordered::<2>(&m, &p, &mut rng);
        jac.border.own[2] = Block::identity();
        let err = s.solve(&jac, &mut rhs.clone());
        assert_eq!(
            err,
            Err(LinearSolveError::OutsidePattern { row: n, col: n + 2 })
        );
        // Slot 3 with node 5.
        let mut jac = random_bordered::<2>(&m, &p, &mut rng);
        jac.border
            .links
            .push((5, 3, Block::identity(), Block::identity()));
        let err = s.solve(&jac, &mut rhs.clone());
        assert_eq!(
            err,
            Err(LinearSolveError::OutsidePattern { row: n + 3, col: 5 })
        );
        // A system without the slots.
        let jac = random_jac::<2>(&m, &mut rng);
        let err = s.solve(&jac, &mut rhs.clone());
        let expected = n + 4;
        assert_eq!(err, Err(LinearSolveError::Unknowns { expected, found: n }));
        // The solver recovers.
        let jac = random_bordered::<2>(&m, &p, &mut rng);
        s.solve(&jac, &mut rhs.clone()).unwrap();
        // Indices out of range at construction.
        let bad = BorderPattern {
            slots: 2,
            links: vec![[n, 0]],
            pairs: vec![],
        };
        let err = NetworkSolver::<2>::with_border(&m, &bad, JunctionLu::Block).unwrap_err();
        assert!(
            matches!(err, SetupError::NodeOutOfRange { node, .. } if node == n),
            "{err:?}"
        );
        let bad = BorderPattern {
            slots: 2,
            links: vec![],
            pairs: vec![[0, 2]],
        };
        let err = NetworkSolver::<2>::with_border(&m, &bad, JunctionLu::Block).unwrap_err();
        assert!(
            matches!(err, SetupError::SlotOutOfRange { slot: 2, .. }),
            "{err:?}"
        );
    }

    #[test]
    fn make_solver_builds_network() {
        let m = grid_net(2, 2, 3, 1);
        let s = make_solver::<3>(SolverKind::Network, &m).unwrap();
        assert_eq!(s.name(), "network");
        assert_eq!(SolverKind::Network.name(), "network");
    }
}
