//! Reference configuration: nodes and 2-node elements with reference lengths (docs/method.md §4).

use crate::error::SetupError;

/// A mesh of 2-node string elements.
///
/// Elements are node pairs `[a, b]` with a reference (unstretched) length `l_e` [m], the
/// length of the element in the material coordinate `s`. Several strings can share nodes.
/// A mesh whose element `e` is `[e, e+1]` for every `e` is a *chain*; chains are solved by
/// the O(N) block-tridiagonal solver.
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    n_nodes: usize,
    elements: Vec<[usize; 2]>,
    lengths: Vec<f64>,
}

impl Mesh {
    /// A chain of `n_el` elements of equal reference length `length / n_el` [m], nodes
    /// `0 … n_el`.
    pub fn uniform_chain(n_el: usize, length: f64) -> Result<Self, SetupError> {
        if n_el == 0 {
            return Err(SetupError::NoElements);
        }
        let l = length / n_el as f64;
        Self::new(
            n_el + 1,
            (0..n_el).map(|e| [e, e + 1]).collect(),
            vec![l; n_el],
        )
    }

    /// A mesh from explicit element node pairs and reference lengths [m].
    pub fn new(
        n_nodes: usize,
        elements: Vec<[usize; 2]>,
        lengths: Vec<f64>,
    ) -> Result<Self, SetupError> {
        if elements.is_empty() {
            return Err(SetupError::NoElements);
        }
        if elements.len() != lengths.len() {
            return Err(SetupError::LengthCount {
                elements: elements.len(),
                lengths: lengths.len(),
            });
        }
        for (e, (&[a, b], &l)) in elements.iter().zip(&lengths).enumerate() {
            for node in [a, b] {
                if node >= n_nodes {
                    return Err(SetupError::NodeOutOfRange {
                        what: "element",
                        node,
                        n_nodes,
                    });
                }
            }
            if a == b {
                return Err(SetupError::DegenerateElement {
                    element: e,
                    node: a,
                });
            }
            if !(l > 0.0 && l.is_finite()) {
                return Err(SetupError::NonPositive {
                    what: "element reference length",
                    index: Some(e),
                    value: l,
                });
            }
        }
        Ok(Self {
            n_nodes,
            elements,
            lengths,
        })
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.n_nodes
    }
    /// Number of elements.
    pub fn n_elements(&self) -> usize {
        self.elements.len()
    }
    /// Element node pairs `[a, b]`.
    pub fn elements(&self) -> &[[usize; 2]] {
        &self.elements
    }
    /// Element reference lengths `l_e` [m].
    pub fn lengths(&self) -> &[f64] {
        &self.lengths
    }
    /// Total reference length `L = Σ l_e` [m].
    pub fn total_length(&self) -> f64 {
        self.lengths.iter().sum()
    }
    /// Whether element `e` is `[e, e+1]` for all `e` and every node is used.
    pub fn is_chain(&self) -> bool {
        self.n_nodes == self.elements.len() + 1
            && self
                .elements
                .iter()
                .enumerate()
                .all(|(e, &[a, b])| a == e && b == e + 1)
    }
}
