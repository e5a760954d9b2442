//! One value of a family indexed by the spatial dimension (1, 2 or 3), chosen at run time:
//! the one place where code generic over `const D: usize` meets a dimension known only from
//! a file. [`by_dim!`](crate::by_dim) applies generic code to whichever variant it holds.

/// A value for dimension 1, 2 or 3: `T1`, `T2` or `T3` (usually one generic type at
/// `D = 1, 2, 3`, e.g. `ByDim<Simulation<1, M>, Simulation<2, M>, Simulation<3, M>>`).
#[derive(Debug, Clone)]
pub enum ByDim<T1, T2, T3> {
    /// The value in one dimension.
    D1(T1),
    /// The value in two dimensions.
    D2(T2),
    /// The value in three dimensions.
    D3(T3),
}

impl<T1, T2, T3> ByDim<T1, T2, T3> {
    /// The spatial dimension, 1, 2 or 3.
    pub fn dimension(&self) -> usize {
        match self {
            Self::D1(_) => 1,
            Self::D2(_) => 2,
            Self::D3(_) => 3,
        }
    }
}

impl<T1, T2, T3, E> ByDim<Result<T1, E>, Result<T2, E>, Result<T3, E>> {
    /// The value, or the error, of a fallible result in each dimension (after
    /// `by_dim!(map …)` of fallible code).
    pub fn transpose(self) -> Result<ByDim<T1, T2, T3>, E> {
        Ok(match self {
            Self::D1(r) => ByDim::D1(r?),
            Self::D2(r) => ByDim::D2(r?),
            Self::D3(r) => ByDim::D3(r?),
        })
    }
}

/// Applies generic code to the value a [`ByDim`] holds: `by_dim!(x, s => f(s))` evaluates
/// `f(s)` with `s` bound to the variant's value (by value, `&` or `&mut` as `x` is), and
/// `by_dim!(map x, s => g(s))` wraps the result in the same variant. The body is compiled
/// once per dimension; inside it, a const generic `D` is inferred from `s`.
#[macro_export]
macro_rules! by_dim {
    (map $x:expr, $s:ident => $body:expr) => {
        match $x {
            $crate::ByDim::D1($s) => $crate::ByDim::D1($body),
            $crate::ByDim::D2($s) => $crate::ByDim::D2($body),
            $crate::ByDim::D3($s) => $crate::ByDim::D3($body),
        }
    };
    ($x:expr, $s:ident => $body:expr) => {
        match $x {
            $crate::ByDim::D1($s) => $body,
            $crate::ByDim::D2($s) => $body,
            $crate::ByDim::D3($s) => $body,
        }
    };
}

#[cfg(test)]
mod tests {
    use super::ByDim;
    use crate::Vector;

    fn norm<const D: usize>(v: &Vector<D>) -> f64 {
        v.norm()
    }

    #[test]
    fn the_macro_runs_the_generic_code_of_the_held_dimension() {
        let values: [ByDim<Vector<1>, Vector<2>, Vector<3>>; 3] = [
            ByDim::D1(Vector::<1>::new(-2.0)),
            ByDim::D2(Vector::<2>::new(3.0, 4.0)),
            ByDim::D3(Vector::<3>::new(2.0, 3.0, 6.0)),
        ];
        let norms: Vec<f64> = values.iter().map(|x| by_dim!(x, v => norm(v))).collect();
        assert_eq!(norms, [2.0, 5.0, 7.0]);
        let dims: Vec<usize> = values.iter().map(ByDim::dimension).collect();
        assert_eq!(dims, [1, 2, 3]);
        let doubled = by_dim!(map values[1].clone(), v => v * 2.0);
        assert!(matches!(doubled, ByDim::D2(v) if v == Vector::<2>::new(6.0, 8.0)));
        let checked = by_dim!(map values[2].clone(), v => {
            if v.norm() > 5.0 { Err(v.norm()) } else { Ok(v) }
        });
        assert_eq!(checked.transpose().unwrap_err(), 7.0);
    }
}
