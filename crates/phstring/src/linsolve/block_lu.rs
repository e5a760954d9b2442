//! Block sparse LU without pivoting between blocks, for the reduced junction system of
//! [`super::NetworkSolver`]: a supernodal multifrontal factorization of a matrix of `D×D`
//! blocks whose (structurally symmetric) pattern is known at construction.
//!
//! **Symbolic phase** ([`BlockLu::new`], once): approximate-minimum-degree ordering of the
//! block graph (faer's AMD: on the 50 × 50 junction grid of the benchmark net it needs about
//! as many block products as a nested dissection by level structures, 1.00 M against
//! 0.97 M), the block structure of the factor column by column (the lower neighbours of a
//! column and the structures of its children in the elimination tree), *supernodes* (runs of
//! consecutive columns `j, j+1, …` with `struct(j) = {j+1} ∪ struct(j+1)`), their dense
//! storage, the positions of every supernode's rows among the rows of its parent, and a
//! first-fit placement of the update matrices in one arena, so that the numeric phase does no
//! searching and no allocation.
//!
//! **Numeric phase** ([`BlockLu::factor`], per solve): `A = L Ũ` with `L` unit block lower
//! triangular and `Ũ` block upper triangular with the pivot blocks `P_j` on its diagonal.
//! Supernodes are processed in order; supernode `s` with columns `S` and rows below `R`
//! 1. adds the parts of its children's update matrices that fall into its columns or rows
//!    (precomputed positions, runs of consecutive rows added as slices);
//! 2. factors its dense diagonal block `A_SS = L_SS Ũ_SS` blockwise (recursively halved,
//!    `D×D` pivots inverted with `try_inverse`, no pivoting between blocks);
//! 3. computes `L_RS = A_RS Ũ_SS⁻¹` and `Ũ_SR = L_SS⁻¹ A_SR` (faer's dense triangular
//!    solves) and its own update matrix `−L_RS Ũ_SR` on `R × R` (faer's dense product);
//! 4. adds the rest of its children's update matrices to its own, which its parent takes
//!    over.
//!
//! Safe without pivoting for mass-dominated matrices (the Newton matrix `(2/h²) M + K`); a
//! pivot block that cannot be inverted is reported with its row.
//!
//! **Storage** of supernode `s` (width `w`, `h` rows below; scalar, column-major): the
//! `(w + h)D × wD` panel `[A_SS; A_RS]` → `[L_SS \ U_SS; L_RS]`, where the diagonal block
//! holds the strictly lower blocks of `L_SS` and the strictly upper blocks of
//! `U_SS = diag(P)⁻¹ Ũ_SS` around identity diagonal blocks (both unit triangular as scalar
//! matrices), then the `hD × wD` panel `A_SRᵀ` → `Ũ_SRᵀ`; the inverted pivots are kept
//! apart.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::solve_unit_lower_triangular_in_place;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::SymbolicSparseColMatRef;
use faer::sparse::linalg::amd;
use faer::{Accum, MatMut, MatRef, Par};
use nalgebra::SVector;

use super::Block;

/// Where a block of the matrix is assembled in a [`BlockLu`] (see [`BlockLu::slot`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Slot(usize);

/// Where a block lies in the factor storage: entry `(k, l)` at `base + k·rs + l·cs`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct FacPos {
    base: usize,
    rs: usize,
    cs: usize,
}

/// A supernode: consecutive block columns with the same structure below them.
#[derive(Debug, Clone, Copy)]
struct Supernode {
    /// First block column.
    first: usize,
    /// Number of block columns `w`.
    width: usize,
    /// Start of the rows below the supernode in `BlockLu::rows`.
    rows: usize,
    /// Number of block rows `h` below the supernode.
    height: usize,
    /// Offset of the supernode's factor storage in `BlockLu::fac`.
    fac: usize,
    /// Offset of its `hD × hD` update matrix in `BlockLu::arena`.
    update: usize,
    /// Its children in the supernodal elimination tree, `BlockLu::children[children]`.
    children: [usize; 2],
    /// Positions of its rows below among the rows of its parent: `BlockLu::rel[rel..rel + h]`.
    rel: usize,
    /// Number of its rows below that are columns of the parent (they come first).
    k: usize,
    /// Runs of consecutive positions in the parent, `BlockLu::segments[segs]`.
    segs: [usize; 2],
}

impl Supernode {
    /// Leading dimension of the `L` panel, `(w + h)·D`.
    fn ld<const D: usize>(&self) -> usize {
        (self.width + self.height) * D
    }
    /// Offset of the `Ũᵀ` panel in `BlockLu::fac`.
    fn up<const D: usize>(&self) -> usize {
        self.fac + self.ld::<D>() * self.width * D
    }
    /// Scalars of factor storage.
    fn len<const D: usize>(&self) -> usize {
        (self.width + 2 * self.height) * self.width * D * D
    }
}

/// Rows `R[r0..r1]` below a child supernode land at the consecutive positions `p0..` among
/// the rows of its parent (the parent's columns first, then its rows below); a segment
/// does not straddle the two parts.
#[derive(Debug, Clone, Copy)]
struct Segment {
    r0: usize,
    r1: usize,
    p0: usize,
}

/// Construction-time first-fit allocator of the update matrices in the arena.
#[derive(Default)]
struct ArenaPlan {
    /// Free ranges `(offset, len)` below `top`, ascending.
    free: Vec<(usize, usize)>,
    top: usize,
    peak: usize,
}

impl ArenaPlan {
    fn alloc(&mut self, len: usize) -> usize {
        if let Some(i) = self.free.iter().position(|&(_, l)| l >= len) {
            let (off, l) = self.free[i];
            if l == len {
                self.free.remove(i);
            } else {
                self.free[i] = (off + len, l - len);
            }
            return off;
        }
        let off = match self.free.last() {
            Some(&(o, l)) if o + l == self.top => {
                self.free.pop();
                o
            }
            _ => self.top,
        };
        self.top = off + len;
        self.peak = self.peak.max(self.top);
        off
    }

    fn release(&mut self, off: usize, len: usize) {
        if len == 0 {
            return;
        }
        let i = self.free.partition_point(|&(o, _)| o < off);
        self.free.insert(i, (off, len));
        // Coalesce with the next and the previous range.
        if i + 1 < self.free.len() && self.free[i].0 + self.free[i].1 == self.free[i + 1].0 {
            self.free[i].1 += self.free[i + 1].1;
            self.free.remove(i + 1);
        }
        if i > 0 && self.free[i - 1].0 + self.free[i - 1].1 == self.free[i].0 {
            self.free[i - 1].1 += self.free[i].1;
            self.free.remove(i);
        }
        if let Some(&(o, l)) = self.free.last()
            && o + l == self.top
        {
            self.free.pop();
            self.top = o;
        }
    }
}

/// Block sparse LU of an `n × n` matrix of `D×D` blocks with a structurally symmetric
/// pattern known at construction; see the [module documentation](self).
pub(crate) struct BlockLu<const D: usize> {
    /// `perm[new] = old`.
    perm: Vec<usize>,
    /// `inv_perm[old] = new`.
    inv_perm: Vec<usize>,
    supernodes: Vec<Supernode>,
    /// Supernode of every block column (new numbering).
    supernode_of: Vec<usize>,
    /// Rows below the supernodes (new numbering, ascending per supernode).
    rows: Vec<usize>,
    children: Vec<usize>,
    rel: Vec<usize>,
    segments: Vec<Segment>,
    /// Factor storage of all supernodes.
    fac: Vec<f64>,
    /// Update matrices of the supernodes whose parents are not factored yet.
    arena: Vec<f64>,
    /// Inverted pivot blocks (new numbering).
    pinv: Vec<Block<D>>,
    /// The assembled blocks of the pattern, ordered by the supernode they belong to.
    values: Vec<Block<D>>,
    /// Blocks `(i, j)` of the pattern (new numbering) with their index in `values`, sorted.
    lookup: Vec<([usize; 2], usize)>,
    /// Position in the factor storage of every block in `values`.
    value_pos: Vec<FacPos>,
    /// The blocks of supernode `s` are `values[value_ptr[s]..value_ptr[s + 1]]`.
    value_ptr: Vec<usize>,
    /// Assembly slots of the diagonal blocks (original numbering).
    diag_slots: Vec<Slot>,
    /// Permuted right-hand side and solution, `n·D`.
    x: Vec<f64>,
    /// Rows below one supernode in the solves, `max h·D`.
    work: Vec<f64>,
    /// Blocks in the strictly lower triangle of `L` (as many in `Ũ`).
    nnz_l: usize,
    /// `D×D` block products of one factorization.
    n_products: usize,
}

impl<const D: usize> std::fmt::Debug for BlockLu<D> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BlockLu")
            .field("n", &self.perm.len())
            .field("supernodes", &self.supernodes.len())
            .field("nnz_l", &self.nnz_l)
            .field("block_products", &self.n_products)
            .finish_non_exhaustive()
    }
}

/// Symmetric adjacency (no diagonal, sorted, deduplicated) in CSR form.
fn adjacency(n: usize, pairs: &[[usize; 2]]) -> (Vec<usize>, Vec<usize>) {
    let mut lists: Vec<Vec<usize>> = vec![Vec::new(); n];
    for &[a, b] in pairs {
        if a != b {
            lists[a].push(b);
            lists[b].push(a);
        }
    }
    let mut ptr = Vec::with_capacity(n + 1);
    ptr.push(0);
    let mut idx = Vec::new();
    for l in &mut lists {
        l.sort_unstable();
        l.dedup();
        idx.extend_from_slice(l);
        ptr.push(idx.len());
    }
    (ptr, idx)
}

/// AMD ordering of the graph `(ptr, idx)`: `perm[new] = old`.
fn amd_order(ptr: &[usize], idx: &[usize]) -> Vec<usize> {
    let n = ptr.len() - 1;
    if idx.is_empty() {
        return (0..n).collect();
    }
    let mut perm = vec![0usize; n];
    let mut perm_inv = vec![0usize; n];
    let a = SymbolicSparseColMatRef::new_checked(n, n, ptr, None, idx);
    let mut mem = MemBuffer::new(amd::order_scratch::<usize>(n, idx.len()));
    amd::order(
        &mut perm,
        &mut perm_inv,
        a,
        amd::Control::default(),
        MemStack::new(&mut mem),
    )
    .expect("AMD ordering of a valid pattern");
    perm
}

/// Block structure of the strictly lower triangle of `L` by columns (new numbering): the
/// lower neighbours of `j` and the structures of the children of `j` in the elimination
/// tree, without `j`. Returns `(col_ptr, row_idx)`, rows ascending.
fn column_structures(
    aptr: &[usize],
    aidx: &[usize],
    perm: &[usize],
    inv_perm: &[usize],
) -> (Vec<usize>, Vec<usize>) {
    let n = perm.len();
    let none = usize::MAX;
    let mut first_child = vec![none; n];
    let mut next_sibling = vec![none; n];
    let mut mark = vec![none; n];
    let mut col_ptr = Vec::with_capacity(n + 1);
    let mut row_idx = Vec::new();
    col_ptr.push(0);
    for j in 0..n {
        let start = row_idx.len();
        mark[j] = j;
        let old = perm[j];
        for &o in &aidx[aptr[old]..aptr[old + 1]] {
            let i = inv_perm[o];
            if i > j && mark[i] != j {
                mark[i] = j;
                row_idx.push(i);
            }
        }
        let mut c = first_child[j];
        while c != none {
            for q in col_ptr[c]..col_ptr[c + 1] {
                let i = row_idx[q];
                if i > j && mark[i] != j {
                    mark[i] = j;
                    row_idx.push(i);
                }
            }
            c = next_sibling[c];
        }
        row_idx[start..].sort_unstable();
        // The parent of j is its first row below.
        if let Some(&p) = row_idx.get(start) {
            next_sibling[j] = first_child[p];
            first_child[p] = j;
        }
        col_ptr.push(row_idx.len());
    }
    (col_ptr, row_idx)
}

/// Reads block `(r, c)` of `a`.
#[inline]
fn get_block<const D: usize>(a: &MatMut<'_, f64>, r: usize, c: usize) -> Block<D> {
    Block::from_fn(|k, l| a[(r * D + k, c * D + l)])
}

/// Writes block `(r, c)` of `a`.
#[inline]
fn set_block<const D: usize>(a: &mut MatMut<'_, f64>, r: usize, c: usize, b: &Block<D>) {
    for l in 0..D {
        for k in 0..D {
            a[(r * D + k, c * D + l)] = b[(k, l)];
        }
    }
}

/// `a[:, c] ← a[:, c] · pinv[c]` for every block column `c` of `a`.
fn scale_block_cols<const D: usize>(a: &mut MatMut<'_, f64>, pinv: &[Block<D>]) {
    for (c, p) in pinv.iter().enumerate() {
        for r in 0..a.nrows() / D {
            let b = get_block::<D>(a, r, c) * p;
            set_block(a, r, c, &b);
        }
    }
}

/// `a[r, c] ← a[r, c] · pinv[c]` for the blocks of the scalar rows `row0..ld` of the
/// column-major panel `a` with leading dimension `ld` and `pinv.len()` block columns.
fn scale_panel_cols<const D: usize>(a: &mut [f64], ld: usize, row0: usize, pinv: &[Block<D>]) {
    for (cols, p) in a.chunks_exact_mut(D * ld).zip(pinv) {
        let mut it = cols.chunks_exact_mut(ld);
        let mut c: [&mut [f64]; D] = std::array::from_fn(|_| it.next().expect("D columns"));
        for r in (row0..ld).step_by(D) {
            let b = Block::<D>::from_fn(|k, l| c[l][r + k]);
            let s = b * p;
            for (l, col) in c.iter_mut().enumerate() {
                for k in 0..D {
                    col[r + k] = s[(k, l)];
                }
            }
        }
    }
}

/// `a[r, :] ← pinv[r] · a[r, :]` for every block row `r` of `a`.
fn scale_block_rows<const D: usize>(a: &mut MatMut<'_, f64>, pinv: &[Block<D>]) {
    for (r, p) in pinv.iter().enumerate() {
        for c in 0..a.ncols() / D {
            let b = p * get_block::<D>(a, r, c);
            set_block(a, r, c, &b);
        }
    }
}

/// `dst += src`.
#[inline]
fn add_to(dst: &mut [f64], src: &[f64]) {
    for (d, s) in dst.iter_mut().zip(src) {
        *d += s;
    }
}
/// The disjoint ranges `a` (mutable) and `b` of `v`.
fn disjoint(
    v: &mut [f64],
    a: std::ops::Range<usize>,
    b: std::ops::Range<usize>,
) -> (&mut [f64], &[f64]) {
    if a.start >= b.end {
        let (lo, hi) = v.split_at_mut(a.start);
        (&mut hi[..a.end - a.start], &lo[b])
    } else {
        assert!(a.end <= b.start, "overlapping update matrices");
        let (lo, hi) = v.split_at_mut(b.start);
        (&mut lo[a], &hi[..b.end - b.start])
    }
}

/// Diagonal blocks of at most this many block columns are factored block by block.
const SMALL: usize = 8;

/// Block `(r, c)` of the column-major matrix `a` (leading dimension `ld`) from `off`.
#[inline]
fn read_block<const D: usize>(a: &[f64], ld: usize, off: usize, r: usize, c: usize) -> Block<D> {
    Block::from_fn(|k, l| a[off + (c * D + l) * ld + r * D + k])
}

/// Writes block `(r, c)` of the column-major matrix `a` (leading dimension `ld`) from `off`.
#[inline]
fn write_block<const D: usize>(
    a: &mut [f64],
    ld: usize,
    off: usize,
    r: usize,
    c: usize,
    b: &Block<D>,
) {
    for l in 0..D {
        let col = &mut a[off + (c * D + l) * ld + r * D..][..D];
        col.copy_from_slice(b.column(l).as_slice());
    }
}

/// Factors the dense square block matrix of `w = pinv.len()` block rows starting at `off`
/// in the column-major `a` (leading dimension `ld`) in place into the strictly lower blocks
/// of `L`, the strictly upper blocks of `U = diag(P)⁻¹ Ũ` and identity diagonal blocks;
/// `pinv` receives the inverted pivots. A pivot that cannot be inverted is an error with
/// its block index.
fn factor_dense<const D: usize>(
    a: &mut [f64],
    ld: usize,
    off: usize,
    pinv: &mut [Block<D>],
) -> Result<(), usize> {
    let w = pinv.len();
    if w <= SMALL {
        for k in 0..w {
            let inv = read_block::<D>(a, ld, off, k, k).try_inverse().ok_or(k)?;
            pinv[k] = inv;
            write_block(a, ld, off, k, k, &Block::<D>::identity());
            for i in k + 1..w {
                let l = read_block::<D>(a, ld, off, i, k) * inv;
                write_block(a, ld, off, i, k, &l);
            }
            for j in k + 1..w {
                let u = read_block::<D>(a, ld, off, k, j);
                for i in k + 1..w {
                    let b =
                        read_block::<D>(a, ld, off, i, j) - read_block::<D>(a, ld, off, i, k) * u;
                    write_block(a, ld, off, i, j, &b);
                }
                write_block(a, ld, off, k, j, &(inv * u));
            }
        }
        return Ok(());
    }
    let w1 = w / 2;
    let (p1, p2) = pinv.split_at_mut(w1);
    factor_dense(a, ld, off, p1)?;
    {
        let m = MatMut::from_column_major_slice_with_stride_mut(&mut a[off..], w * D, w * D, ld);
        let (a11, mut a12, mut a21, a22) = m.split_at_mut(w1 * D, w1 * D);
        // L21 = A21 Ũ11⁻¹ = (A21 U11⁻¹) P1⁻¹, Ũ12 = L11⁻¹ A12.
        solve_unit_lower_triangular_in_place(
            a11.rb().transpose(),
            a21.rb_mut().transpose_mut(),
            Par::Seq,
        );
        scale_block_cols(&mut a21, p1);
        solve_unit_lower_triangular_in_place(a11.rb(), a12.rb_mut(), Par::Seq);
        matmul(a22, Accum::Add, a21.rb(), a12.rb(), -1.0, Par::Seq);
        scale_block_rows(&mut a12, p1);
    }
    factor_dense(a, ld, off + w1 * D * (ld + 1), p2).map_err(|k| k + w1)
}

/// The supernodes of the column structures `col_ptr`/`row_idx` of `n` block columns (a
/// column continues the supernode of the one before if `struct(j − 1) = {j} ∪ struct(j)`),
/// the supernode of each column, the supernodes' rows below their columns, and the length of
/// the factor's storage.
fn supernodes<const D: usize>(
    n: usize,
    col_ptr: &[usize],
    row_idx: &[usize],
) -> (Vec<Supernode>, Vec<usize>, Vec<usize>, usize) {
    let count = |j: usize| col_ptr[j + 1] - col_ptr[j];
    let mut supernodes: Vec<Supernode> = Vec::new();
    let mut supernode_of = vec![0; n];
    for j in 0..n {
        let continues =
            j > 0 && count(j - 1) == count(j) + 1 && row_idx.get(col_ptr[j - 1]) == Some(&j);
        match supernodes.last_mut() {
            Some(sn) if continues => sn.width += 1,
            _ => supernodes.push(Supernode {
                first: j,
                width: 1,
                rows: 0,
                height: 0,
                fac: 0,
                update: 0,
                children: [0, 0],
                rel: 0,
                k: 0,
                segs: [0, 0],
            }),
        }
        supernode_of[j] = supernodes.len() - 1;
    }
    let mut rows = Vec::new();
    let mut fac_len = 0;
    for sn in &mut supernodes {
        let last = sn.first + sn.width - 1;
        sn.rows = rows.len();
        rows.extend_from_slice(&row_idx[col_ptr[last]..col_ptr[last + 1]]);
        sn.height = rows.len() - sn.rows;
        sn.fac = fac_len;
        fac_len += sn.len::<D>();
    }
    (supernodes, supernode_of, rows, fac_len)
}

/// The supernodal elimination tree (the parent holds the first row below): each supernode's
/// children as `children[child_ptr[s]..child_ptr[s + 1]]`.
fn elimination_tree(
    supernodes: &[Supernode],
    supernode_of: &[usize],
    rows: &[usize],
) -> (Vec<usize>, Vec<usize>) {
    let ns = supernodes.len();
    let parent = |sn: &Supernode| (sn.height > 0).then(|| supernode_of[rows[sn.rows]]);
    let mut child_ptr = vec![0usize; ns + 1];
    for sn in supernodes {
        if let Some(p) = parent(sn) {
            child_ptr[p + 1] += 1;
        }
    }
    for s in 0..ns {
        child_ptr[s + 1] += child_ptr[s];
    }
    let mut fill = child_ptr.clone();
    let mut children = vec![0; child_ptr[ns]];
    for (s, sn) in supernodes.iter().enumerate() {
        if let Some(p) = parent(sn) {
            children[fill[p]] = s;
            fill[p] += 1;
        }
    }
    (child_ptr, children)
}

/// The positions of each supernode's rows below among its parent's rows (`rel`), in runs
/// (`segments`); records each supernode's children, offsets and the count of its rows that
/// fall in the parent's columns.
fn relative_rows(
    supernodes: &mut [Supernode],
    supernode_of: &[usize],
    rows: &[usize],
    child_ptr: &[usize],
    n: usize,
) -> (Vec<usize>, Vec<Segment>) {
    let ns = supernodes.len();
    let parent = |sn: &Supernode| (sn.height > 0).then(|| supernode_of[rows[sn.rows]]);
    let mut position = vec![usize::MAX; n];
    let mut rel = Vec::new();
    let mut segments: Vec<Segment> = Vec::new();
    for s in 0..ns {
        supernodes[s].children = [child_ptr[s], child_ptr[s + 1]];
        let sn = supernodes[s];
        let Some(p) = parent(&sn) else { continue };
        let t = supernodes[p];
        let t_rows =
            (t.first..t.first + t.width).chain(rows[t.rows..t.rows + t.height].iter().copied());
        for (q, i) in t_rows.clone().enumerate() {
            position[i] = q;
        }
        let seg0 = segments.len();
        let rel0 = rel.len();
        for (r, &i) in rows[sn.rows..sn.rows + sn.height].iter().enumerate() {
            let q = position[i];
            assert!(q != usize::MAX, "update outside the symbolic pattern");
            rel.push(q);
            match segments[seg0..].last_mut() {
                Some(g) if g.p0 + (r - g.r0) == q && q != t.width => g.r1 = r + 1,
                _ => segments.push(Segment {
                    r0: r,
                    r1: r + 1,
                    p0: q,
                }),
            }
        }
        for i in t_rows {
            position[i] = usize::MAX;
        }
        let k = rel[rel0..].iter().take_while(|&&q| q < t.width).count();
        let sn = &mut supernodes[s];
        sn.rel = rel0;
        sn.k = k;
        sn.segs = [seg0, segments.len()];
    }
    (rel, segments)
}

impl<const D: usize> BlockLu<D> {
    /// Analyses the pattern of `n` diagonal blocks and the blocks `(a, b)` and `(b, a)` of
    /// every pair in `pairs` (pairs with `a == b` add nothing).
    pub(crate) fn new(n: usize, pairs: &[[usize; 2]]) -> Self {
        let (aptr, aidx) = adjacency(n, pairs);
        let perm = amd_order(&aptr, &aidx);
        let mut inv_perm = vec![0; n];
        for (new, &old) in perm.iter().enumerate() {
            inv_perm[old] = new;
        }
        let (col_ptr, row_idx) = column_structures(&aptr, &aidx, &perm, &inv_perm);
        let count = |j: usize| col_ptr[j + 1] - col_ptr[j];
        let (mut supernodes, supernode_of, rows, fac_len) = supernodes::<D>(n, &col_ptr, &row_idx);
        let max_height = supernodes.iter().map(|s| s.height).max().unwrap_or(0);
        let (child_ptr, children) = elimination_tree(&supernodes, &supernode_of, &rows);
        let (rel, segments) = relative_rows(&mut supernodes, &supernode_of, &rows, &child_ptr, n);
        // Update matrices live from their supernode's factorization to their parent's.
        let mut plan = ArenaPlan::default();
        for s in 0..supernodes.len() {
            let h = supernodes[s].height;
            supernodes[s].update = plan.alloc(h * h * D * D);
            for c in child_ptr[s]..child_ptr[s + 1] {
                let child = supernodes[children[c]];
                plan.release(child.update, child.height * child.height * D * D);
            }
        }
        let n_products = (0..n).map(|j| count(j) * count(j)).sum();
        let mut lu = Self {
            perm,
            inv_perm,
            supernodes,
            supernode_of,
            rows,
            children,
            rel,
            segments,
            fac: vec![0.0; fac_len],
            arena: vec![0.0; plan.peak],
            pinv: vec![Block::zeros(); n],
            values: Vec::new(),
            lookup: Vec::new(),
            value_pos: Vec::new(),
            value_ptr: Vec::new(),
            diag_slots: Vec::new(),
            x: vec![0.0; n * D],
            work: vec![0.0; max_height * D],
            nnz_l: row_idx.len(),
            n_products,
        };
        lu.lay_out_values(pairs);
        // A warm-up factorization of the identity lets faer's dense kernels size their
        // (thread-local) work space here rather than in the first solve.
        for a in 0..n {
            lu.add_diag(a, &Block::identity());
        }
        lu.factor().expect("the identity has invertible pivots");
        lu.clear();
        lu
    }

    /// The slots of the pattern's blocks (`n` diagonal blocks and both orders of every pair
    /// in `pairs` with `a ≠ b`), grouped by the supernode whose panels hold them.
    fn lay_out_values(&mut self, pairs: &[[usize; 2]]) {
        let lu = self;
        let n = lu.inv_perm.len();
        let owner = |[i, j]: [usize; 2]| lu.supernode_of[i.min(j)];
        let mut blocks: Vec<[usize; 2]> = (0..n).map(|j| [j, j]).collect();
        for &[a, b] in pairs.iter().filter(|[a, b]| a != b) {
            let (i, j) = (lu.inv_perm[a], lu.inv_perm[b]);
            blocks.extend([[i, j], [j, i]]);
        }
        blocks.sort_unstable_by_key(|&ij| (owner(ij), ij));
        blocks.dedup();
        lu.value_ptr = vec![0; lu.supernodes.len() + 1];
        for &ij in &blocks {
            lu.value_ptr[owner(ij) + 1] += 1;
        }
        for s in 0..lu.supernodes.len() {
            lu.value_ptr[s + 1] += lu.value_ptr[s];
        }
        lu.value_pos = blocks.iter().map(|&[i, j]| lu.fac_pos(i, j)).collect();
        lu.lookup = blocks.iter().enumerate().map(|(v, &ij)| (ij, v)).collect();
        lu.lookup.sort_unstable();
        lu.values = vec![Block::zeros(); blocks.len()];
        lu.diag_slots = (0..n)
            .map(|a| lu.block_slot(lu.inv_perm[a], lu.inv_perm[a]))
            .collect();
    }

    /// Position of block row `i` among the rows of supernode `t` (its columns first).
    fn position(&self, t: &Supernode, i: usize) -> usize {
        if (t.first..t.first + t.width).contains(&i) {
            i - t.first
        } else {
            t.width
                + self.rows[t.rows..t.rows + t.height]
                    .binary_search(&i)
                    .expect("block is in the pattern")
        }
    }

    /// Assembly slot of block `(i, j)` (new numbering) of the pattern.
    fn block_slot(&self, i: usize, j: usize) -> Slot {
        let k = self
            .lookup
            .binary_search_by_key(&[i, j], |&(ij, _)| ij)
            .expect("block is in the pattern");
        Slot(self.lookup[k].1)
    }

    /// Position of block `(i, j)` (new numbering) in the factor storage.
    fn fac_pos(&self, i: usize, j: usize) -> FacPos {
        if i >= j {
            // Column j of the L panel.
            let t = &self.supernodes[self.supernode_of[j]];
            let ld = t.ld::<D>();
            let p = self.position(t, i);
            FacPos {
                base: t.fac + (j - t.first) * D * ld + p * D,
                rs: 1,
                cs: ld,
            }
        } else {
            // Row i of the diagonal block or of the transposed U panel.
            let t = &self.supernodes[self.supernode_of[i]];
            let ld = t.ld::<D>();
            let p = self.position(t, j);
            let c = i - t.first;
            if p < t.width {
                FacPos {
                    base: t.fac + p * D * ld + c * D,
                    rs: 1,
                    cs: ld,
                }
            } else {
                let ldu = t.height * D;
                FacPos {
                    base: t.up::<D>() + c * D * ldu + (p - t.width) * D,
                    rs: ldu,
                    cs: 1,
                }
            }
        }
    }

    /// The storage of the off-diagonal block `(a, b)`, `a ≠ b`, which must be in the pattern
    /// given to [`BlockLu::new`]. Searches; call at construction, not per solve.
    pub(crate) fn slot(&self, a: usize, b: usize) -> Slot {
        assert_ne!(a, b, "diagonal blocks have no slot");
        self.block_slot(self.inv_perm[a], self.inv_perm[b])
    }

    /// Sets all blocks to zero (before assembling new values).
    pub(crate) fn clear(&mut self) {
        self.values.fill(Block::zeros());
    }

    /// Adds `blk` to the block assembled at `slot`.
    #[inline]
    pub(crate) fn add(&mut self, slot: Slot, blk: &Block<D>) {
        self.values[slot.0] += blk;
    }

    /// Adds `blk` to the diagonal block of row `a`.
    #[inline]
    pub(crate) fn add_diag(&mut self, a: usize, blk: &Block<D>) {
        self.add(self.diag_slots[a], blk);
    }

    /// Factors the assembled matrix in place (see the [module documentation](self)). A
    /// pivot block that cannot be inverted is an error with its row (original numbering);
    /// the factors are then invalid until the next assembly and factorization.
    pub(crate) fn factor(&mut self) -> Result<(), usize> {
        for s in 0..self.supernodes.len() {
            let sn = self.supernodes[s];
            // The supernode's storage: zero, then its assembled blocks (just before use, so
            // that it is in cache).
            self.fac[sn.fac..sn.fac + sn.len::<D>()].fill(0.0);
            let vals = self.value_ptr[s]..self.value_ptr[s + 1];
            for (blk, pos) in self.values[vals.clone()].iter().zip(&self.value_pos[vals]) {
                for l in 0..D {
                    for k in 0..D {
                        self.fac[pos.base + k * pos.rs + l * pos.cs] = blk[(k, l)];
                    }
                }
            }
            let kids = sn.children[0]..sn.children[1];
            for i in kids.clone() {
                let c = self.supernodes[self.children[i]];
                self.add_to_panels(&c, &sn);
            }
            let (w, h) = (sn.width, sn.height);
            let (wd, hd, ld) = (w * D, h * D, sn.ld::<D>());
            let (lp, up) = self.fac[sn.fac..sn.fac + sn.len::<D>()].split_at_mut(ld * wd);
            let pinv = &mut self.pinv[sn.first..sn.first + w];
            factor_dense(lp, ld, 0, pinv).map_err(|k| self.perm[sn.first + k])?;
            if h == 0 {
                continue;
            }
            if w > 1 {
                // L_RS U_SS = A_RS (then P_S⁻¹ below), L_SS Ũ_SR = A_SR.
                let panel = MatMut::from_column_major_slice_mut(&mut *lp, ld, wd);
                let (diag, below) = panel.split_at_row_mut(wd);
                let up = MatMut::from_column_major_slice_mut(&mut *up, hd, wd);
                solve_unit_lower_triangular_in_place(
                    diag.rb().transpose(),
                    below.transpose_mut(),
                    Par::Seq,
                );
                solve_unit_lower_triangular_in_place(diag.rb(), up.transpose_mut(), Par::Seq);
            }
            scale_panel_cols(lp, ld, wd, pinv);
            let below = MatRef::from_column_major_slice_with_stride(&lp[wd..], hd, wd, ld);
            let up = MatRef::from_column_major_slice(up, hd, wd);
            let update = &mut self.arena[sn.update..sn.update + hd * hd];
            matmul(
                MatMut::from_column_major_slice_mut(update, hd, hd),
                Accum::Replace,
                below,
                up.transpose(),
                -1.0,
                Par::Seq,
            );
            for i in kids {
                let c = self.supernodes[self.children[i]];
                if c.k < c.height {
                    self.add_to_update(&c, &sn);
                }
            }
        }
        Ok(())
    }

    /// Adds the blocks of child `c`'s update matrix whose row or column is a column of its
    /// parent `t` to `t`'s `L` panel (columns of `t`) and transposed `U` panel.
    fn add_to_panels(&mut self, c: &Supernode, t: &Supernode) {
        let (hc, k) = (c.height, c.k);
        let hcd = hc * D;
        let cu = &self.arena[c.update..c.update + hcd * hcd];
        let rel = &self.rel[c.rel..c.rel + hc];
        let segs = &self.segments[c.segs[0]..c.segs[1]];
        let (ld, ldu, wt) = (t.ld::<D>(), t.height * D, t.width);
        for q in 0..k {
            let pq = rel[q];
            for l in 0..D {
                // A column of t: the whole column goes to the L panel.
                let src = &cu[(q * D + l) * hcd..][..hcd];
                let col = t.fac + (pq * D + l) * ld;
                for g in segs {
                    let len = (g.r1 - g.r0) * D;
                    add_to(
                        &mut self.fac[col + g.p0 * D..][..len],
                        &src[g.r0 * D..][..len],
                    );
                }
            }
        }
        // Blocks (column of t, row below t) of Ũ, stored transposed.
        for (r, &pr) in rel[..k].iter().enumerate() {
            for kk in 0..D {
                let col = t.up::<D>() + (pr * D + kk) * ldu;
                for (q, &pq) in rel.iter().enumerate().skip(k) {
                    let dst = &mut self.fac[col + (pq - wt) * D..][..D];
                    for (l, d) in dst.iter_mut().enumerate() {
                        *d += cu[(q * D + l) * hcd + r * D + kk];
                    }
                }
            }
        }
    }

    /// Adds the blocks of child `c`'s update matrix with row and column below its parent
    /// `t` to `t`'s update matrix.
    fn add_to_update(&mut self, c: &Supernode, t: &Supernode) {
        let (hc, k) = (c.height, c.k);
        let (hcd, htd) = (hc * D, t.height * D);
        let (dst, src) = disjoint(
            &mut self.arena,
            t.update..t.update + htd * htd,
            c.update..c.update + hcd * hcd,
        );
        let rel = &self.rel[c.rel..c.rel + hc];
        let segs = &self.segments[c.segs[0]..c.segs[1]];
        let first = segs.partition_point(|g| g.r0 < k);
        for q in k..hc {
            let uq = rel[q] - t.width;
            for l in 0..D {
                let s = &src[(q * D + l) * hcd..][..hcd];
                let col = (uq * D + l) * htd;
                for g in &segs[first..] {
                    let len = (g.r1 - g.r0) * D;
                    let d = &mut dst[col + (g.p0 - t.width) * D..][..len];
                    add_to(d, &s[g.r0 * D..][..len]);
                }
            }
        }
    }

    /// Solves `A x = b` in place with the factors of the last successful
    /// [`BlockLu::factor`], where row `r` of `b` and `x` is `v[rows[r]]`.
    pub(crate) fn solve_indexed(&mut self, v: &mut [SVector<f64, D>], rows: &[usize]) {
        let x = &mut self.x;
        for (new, &old) in self.perm.iter().enumerate() {
            x[new * D..(new + 1) * D].copy_from_slice(v[rows[old]].as_slice());
        }
        // L y = b; the rows below a supernode are updated through the contiguous `t`.
        for sn in &self.supernodes {
            let (wd, hd, ld, f) = (sn.width * D, sn.height * D, sn.ld::<D>(), sn.first * D);
            let t = &mut self.work[..hd];
            t.fill(0.0);
            for c in 0..wd {
                let col = &self.fac[sn.fac + c * ld..][..ld];
                let xc = x[f + c];
                for r in c + 1..wd {
                    x[f + r] -= col[r] * xc;
                }
                for (ti, l) in t.iter_mut().zip(&col[wd..]) {
                    *ti += l * xc;
                }
            }
            let below = &self.rows[sn.rows..sn.rows + sn.height];
            for (&i, ti) in below.iter().zip(t.chunks_exact(D)) {
                for (xi, ti) in x[i * D..(i + 1) * D].iter_mut().zip(ti) {
                    *xi -= ti;
                }
            }
        }
        // Ũ x = y, with Ũ_SS = P U_SS.
        for sn in self.supernodes.iter().rev() {
            let (wd, ld, f) = (sn.width * D, sn.ld::<D>(), sn.first * D);
            let below = &self.rows[sn.rows..sn.rows + sn.height];
            let ldu = sn.height * D;
            let t = &mut self.work[..ldu];
            for (&i, ti) in below.iter().zip(t.chunks_exact_mut(D)) {
                ti.copy_from_slice(&x[i * D..(i + 1) * D]);
            }
            for c in 0..wd {
                let col = &self.fac[sn.up::<D>() + c * ldu..][..ldu];
                let s: f64 = col.iter().zip(t.iter()).map(|(u, xi)| u * xi).sum();
                x[f + c] -= s;
            }
            for (b, p) in self.pinv[sn.first..sn.first + sn.width].iter().enumerate() {
                let xb = &mut x[f + b * D..f + (b + 1) * D];
                let y = p * SVector::<f64, D>::from_column_slice(xb);
                xb.copy_from_slice(y.as_slice());
            }
            for c in (0..wd).rev() {
                let col = &self.fac[sn.fac + c * ld..][..c];
                let xc = x[f + c];
                for (r, u) in col.iter().enumerate() {
                    x[f + r] -= u * xc;
                }
            }
        }
        for (new, &old) in self.perm.iter().enumerate() {
            v[rows[old]].copy_from_slice(&x[new * D..(new + 1) * D]);
        }
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{DMatrix, DVector};

    use super::*;

    use crate::linsolve::test_rng::Rng;

    /// Random pairs on `n` nodes: each of `m` pairs uniform (duplicates, both orientations
    /// and `a == b` included).
    fn random_pairs(n: usize, m: usize, rng: &mut Rng) -> Vec<[usize; 2]> {
        (0..m).map(|_| [rng.below(n), rng.below(n)]).collect()
    }

    /// A `k × k` grid with 4-neighbour couplings.
    fn grid(k: usize) -> Vec<[usize; 2]> {
        let mut pairs = Vec::new();
        for r in 0..k {
            for c in 0..k {
                if c + 1 < k {
                    pairs.push([r * k + c, r * k + c + 1]);
                }
                if r + 1 < k {
                    pairs.push([(r + 1) * k + c, r * k + c]);
                }
            }
        }
        pairs
    }

    /// Assembles random mass-dominated values (`diag = (4·degree + 4D)·I + random`, couplings
    /// random and not symmetric, duplicate pairs added up) into `lu` and a dense copy.
    fn assemble<const D: usize>(
        lu: &mut BlockLu<D>,
        n: usize,
        pairs: &[[usize; 2]],
        rng: &mut Rng,
    ) -> DMatrix<f64> {
        let mut dense = DMatrix::zeros(n * D, n * D);
        let add = |dense: &mut DMatrix<f64>, a: usize, b: usize, blk: &Block<D>| {
            for k in 0..D {
                for l in 0..D {
                    dense[(a * D + k, b * D + l)] += blk[(k, l)];
                }
            }
        };
        lu.clear();
        let mut degree = vec![0.0; n];
        for &[a, b] in pairs.iter().filter(|[a, b]| a != b) {
            degree[a] += 1.0;
            degree[b] += 1.0;
        }
        for (a, deg) in degree.iter().enumerate() {
            let d = Block::<D>::from_fn(|_, _| rng.sym())
                + Block::<D>::identity() * (4.0 * deg + 4.0 * D as f64);
            lu.add_diag(a, &d);
            add(&mut dense, a, a, &d);
        }
        for &[a, b] in pairs.iter().filter(|[a, b]| a != b) {
            for (i, j) in [(a, b), (b, a)] {
                let blk = Block::<D>::from_fn(|_, _| rng.sym());
                lu.add(lu.slot(i, j), &blk);
                add(&mut dense, i, j, &blk);
            }
        }
        dense
    }

    /// Factors and solves two random matrices on the pattern with one `BlockLu` and checks
    /// the solutions against a dense LU, with the rows of the right-hand side scattered.
    fn check<const D: usize>(n: usize, pairs: &[[usize; 2]], seed: u64) {
        let mut rng = Rng(seed);
        let mut lu = BlockLu::<D>::new(n, pairs);
        // Row r of the system lives at v[rows[r]] (every other slot is left alone).
        let rows: Vec<usize> = (0..n).map(|r| 2 * r + 1).collect();
        for _ in 0..2 {
            let dense = assemble(&mut lu, n, pairs, &mut rng);
            let b: Vec<SVector<f64, D>> =
                (0..n).map(|_| SVector::from_fn(|_, _| rng.sym())).collect();
            let mut v = vec![SVector::<f64, D>::repeat(7.0); 2 * n + 1];
            for (r, &i) in rows.iter().enumerate() {
                v[i] = b[r];
            }
            lu.factor().unwrap();
            lu.solve_indexed(&mut v, &rows);
            let bf = DVector::from_iterator(n * D, b.iter().flat_map(|x| x.iter().copied()));
            let x = DVector::from_iterator(n * D, rows.iter().flat_map(|&i| v[i].iter().copied()));
            let x_ref = dense.clone().lu().solve(&bf).expect("invertible");
            let diff = (&x - &x_ref).norm() / x_ref.norm().max(1e-300);
            let res = (&dense * &x - &bf).norm() / bf.norm().max(1e-300);
            assert!(
                diff <= 1e-10,
                "D = {D}, n = {n}: block LU vs dense {diff:e}"
            );
            assert!(res <= 1e-10, "D = {D}, n = {n}: residual {res:e}");
            for i in (0..v.len()).step_by(2) {
                assert_eq!(
                    v[i],
                    SVector::<f64, D>::repeat(7.0),
                    "slot {i} not a row was written"
                );
            }
        }
    }

    fn check_all_d(n: usize, pairs: &[[usize; 2]], seed: u64) {
        check::<1>(n, pairs, seed);
        check::<2>(n, pairs, seed + 1);
        check::<3>(n, pairs, seed + 2);
    }

    #[test]
    fn random_patterns_match_dense_lu() {
        let mut rng = Rng(11);
        for case in 0..30 {
            let n = 1 + rng.below(60);
            let m = rng.below(3 * n);
            let pairs = random_pairs(n, m, &mut rng);
            check_all_d(n, &pairs, 100 + case);
        }
    }

    #[test]
    fn disconnected_components_match_dense_lu() {
        // Two random components, a path and isolated nodes, interleaved in the numbering.
        let mut rng = Rng(5);
        let n = 60;
        let mut pairs = Vec::new();
        for _ in 0..40 {
            pairs.push([4 * rng.below(15), 4 * rng.below(15)]);
            pairs.push([4 * rng.below(15) + 1, 4 * rng.below(15) + 1]);
        }
        pairs.extend((0..14).map(|i| [4 * i + 2, 4 * i + 6]));
        check_all_d(n, &pairs, 200);
    }

    #[test]
    fn single_block_and_empty_system() {
        check_all_d(1, &[], 300);
        check_all_d(1, &[[0, 0]], 301);
        let mut lu = BlockLu::<2>::new(0, &[]);
        lu.factor().unwrap();
        lu.solve_indexed(&mut [], &[]);
    }

    #[test]
    fn dense_and_grid_patterns_match_dense_lu() {
        // A complete graph: one supernode wider than SMALL, factored by recursive halving.
        let n = 3 * SMALL + 5;
        let complete: Vec<[usize; 2]> = (0..n).flat_map(|a| (0..a).map(move |b| [a, b])).collect();
        let lu = BlockLu::<2>::new(n, &complete);
        assert_eq!(lu.supernodes.len(), 1);
        check_all_d(n, &complete, 400);
        // A grid: separators of several widths.
        let k = 14;
        let lu = BlockLu::<3>::new(k * k, &grid(k));
        assert!(lu.supernodes.iter().any(|s| s.width > SMALL));
        check_all_d(k * k, &grid(k), 410);
    }

    #[test]
    fn singular_pivot_reports_its_row() {
        let k = 6;
        let pairs = grid(k);
        let mut lu = BlockLu::<2>::new(k * k, &pairs);
        for bad in [0, 14, 35] {
            let mut rng = Rng(bad as u64);
            assemble(&mut lu, k * k, &pairs, &mut rng);
            // Node `bad` is decoupled and its diagonal block is zero: a zero pivot whenever
            // it is eliminated.
            let Slot(d) = lu.diag_slots[bad];
            lu.values[d] = Block::zeros();
            for &[a, b] in pairs.iter().filter(|p| p.contains(&bad)) {
                for (i, j) in [(a, b), (b, a)] {
                    let Slot(v) = lu.slot(i, j);
                    lu.values[v] = Block::zeros();
                }
            }
            assert_eq!(lu.factor(), Err(bad));
        }
        // Good values factor again.
        let mut rng = Rng(9);
        assemble(&mut lu, k * k, &pairs, &mut rng);
        lu.factor().unwrap();
    }

    #[test]
    fn arena_plan_reuses_and_coalesces() {
        let mut plan = ArenaPlan::default();
        let a = plan.alloc(10);
        let b = plan.alloc(5);
        let c = plan.alloc(7);
        assert_eq!((a, b, c, plan.peak), (0, 10, 15, 22));
        plan.release(a, 10);
        plan.release(b, 5);
        // The freed 15 are one range again.
        assert_eq!(plan.alloc(15), 0);
        plan.release(c, 7);
        assert_eq!(plan.alloc(3), 15);
        assert_eq!(plan.peak, 22);
    }
}
