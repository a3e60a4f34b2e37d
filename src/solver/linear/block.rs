//! GMRES's block lower-triangular preconditioner of the (mechanics, temperature) split.

use super::lag::{Lag, Lagged, factor_price, solve_lagged};
use super::ldlt::{Precision, SymFactor};
use super::lu::LaggedLu;
use super::ordering::nodes_of;
use super::submatrix::SubMatrix;
use super::{DAMPED_TOL, Factorization, GMRES_TOL, LinearError};
use crate::dofs::{Pattern, Structure};

/// The GMRES iterations worth one factorisation of the block-triangular preconditioner's
/// blocks (0: never lagged; [`Lag::priced`] caps the budget at [`LAG_MAX_ITS`]). The blocks
/// factor side by side, so the price is the larger block's; an iteration applies both and
/// multiplies by the whole matrix. Priced so, Table 2 H1 (block-plate-3d-tm1) gets 4, 9 and
/// 33.6 at 3k, 20.5k and 147k unknowns (dear from 12); measured at 20.5k and 147k on one
/// thread, a factorisation costs 8 and about 24 iterations.
///
/// The price is read from the factor alone, never from the threads: whether a factor is
/// dear decides how Newton's damped updates are solved, so a price that fell with the
/// threads changed Newton's path with them (on 16 cores, the 147k row took 81 Newton
/// iterations from 4 threads on and 83 at 1 and 2). A factorisation on many threads is
/// cheaper than its price says; the same iterations at every thread count are worth more.
/// Friction's LU block (two-way scenes) is refactored at every factorisation, as before:
/// its stick–slip switches move the tangent between any two iterations.
pub(super) fn block_lag_price(
    fm: Option<&MechanicsFactor>,
    ft: Option<&SymFactor>,
    p: &Pattern,
) -> f64 {
    let Some(MechanicsFactor::Ldlt(m)) = fm else {
        return 0.0;
    };
    let applied = m.apply_flops() + ft.map_or(0.0, SymFactor::apply_flops);
    let flops = m.flops().max(ft.map_or(0.0, SymFactor::flops));
    factor_price(flops, applied, p.n, p.nnz())
}

impl Lagged for BlockTriangular {
    fn lag(&self) -> &Lag {
        &self.lag
    }
    fn lag_mut(&mut self) -> &mut Lag {
        &mut self.lag
    }
    fn mul(&self, x: &[f64], y: &mut [f64]) {
        BlockTriangular::mul(self, x, y)
    }
    fn precondition(&self, r: &[f64], z: &mut [f64]) {
        BlockTriangular::precondition(self, r, z)
    }
    fn refactor(&mut self) -> Result<(), LinearError> {
        BlockTriangular::refactor(self)
    }
}

impl Factorization for BlockTriangular {
    /// Take the whole system's `values` as the current tangent; the blocks are factorised at
    /// once the first time and wherever no lag is worth it, otherwise only when the last
    /// factors no longer precondition it within their budget.
    fn factor(&mut self, values: &[f64]) -> Result<(), LinearError> {
        self.update(values);
        // a dear factor is kept through the damped iterations too, for a looser solve
        self.lag.tol = if self.near { GMRES_TOL } else { DAMPED_TOL };
        if self.lag.next_tangent(self.near || self.lag.dear) {
            self.refactor()?;
        }
        Ok(())
    }

    fn set_near(&mut self, near: bool) {
        self.near = near;
    }

    fn factorisations(&self) -> Option<usize> {
        Some(self.lag.count)
    }

    fn parts(&self) -> Option<super::SolveParts> {
        Some(self.lag.parts)
    }

    fn solve(&mut self, b: &mut [f64]) -> Result<usize, LinearError> {
        solve_lagged(self, b)
    }

    fn entries(&self) -> Option<usize> {
        let mech = self.fm.as_ref().map_or(Some(0), MechanicsFactor::entries)?;
        Some(mech + self.ft.as_ref().map_or(0, |f| f.symbolic.len_val()))
    }

    /// The mechanics block's, the larger, beside which the temperature block factors.
    fn predicted_speedup(&self, threads: f64) -> Option<super::Speedup> {
        match &self.fm {
            Some(MechanicsFactor::Ldlt(m)) => m.tree.as_ref().map(|t| t.speedups(threads)),
            _ => None,
        }
    }

    fn factor_bytes(&self) -> Option<usize> {
        let mech = self.fm.as_ref().map_or(0, MechanicsFactor::bytes);
        Some(mech + self.ft.as_ref().map_or(0, SymFactor::bytes))
    }
}

/// The factor of the mechanics block: LDLᵀ (single precision) where it is symmetric, LU with
/// friction.
pub(super) enum MechanicsFactor {
    Ldlt(Box<SymFactor>),
    Lu(Box<LaggedLu<f32>>),
}

impl MechanicsFactor {
    /// The block, with the values last taken.
    pub(super) fn matrix(&self) -> &SubMatrix {
        match self {
            MechanicsFactor::Ldlt(f) => &f.sub,
            MechanicsFactor::Lu(f) => &f.sub,
        }
    }

    /// Take the block's values from the whole system's `values`.
    pub(super) fn update(&mut self, values: &[f64]) {
        match self {
            MechanicsFactor::Ldlt(f) => f.sub.update(values),
            MechanicsFactor::Lu(f) => f.sub.update(values),
        }
    }

    /// Factorise the block's values as last taken.
    pub(super) fn factor_current(&mut self) -> Result<(), LinearError> {
        match self {
            MechanicsFactor::Ldlt(f) => f.factor_current(),
            MechanicsFactor::Lu(f) => f.refactor(),
        }
    }

    pub(super) fn solve(&self, b: &mut [f64]) {
        match self {
            MechanicsFactor::Ldlt(f) => f.solve(b),
            MechanicsFactor::Lu(f) => f.apply(b),
        }
    }

    pub(super) fn entries(&self) -> Option<usize> {
        match self {
            MechanicsFactor::Ldlt(f) => Some(f.symbolic.len_val()),
            MechanicsFactor::Lu(f) => Some(f.staticlu.entries()),
        }
    }

    pub(super) fn bytes(&self) -> usize {
        match self {
            MechanicsFactor::Ldlt(f) => f.bytes(),
            MechanicsFactor::Lu(f) => f.bytes(),
        }
    }
}

/// GMRES with the block lower-triangular preconditioner of the (mechanics, temperature) split.
pub(super) struct BlockTriangular {
    /// Global equations of each block.
    pub(super) mech: Vec<usize>,
    pub(super) heat: Vec<usize>,
    pub(super) fm: Option<MechanicsFactor>,
    pub(super) ft: Option<SymFactor>,
    /// K_θm: temperature rows, mechanics columns.
    pub(super) coupling: SubMatrix,
    /// K_mθ: mechanics rows, temperature columns. With the diagonal blocks (held by their
    /// factors) and K_θm, the whole matrix for GMRES's products, without a copy of it.
    pub(super) coupling_mt: SubMatrix,
    /// Budget ([`block_lag_price`]) and state of the factors held.
    pub(super) lag: Lag,
    /// The tangent is near the last factorised one ([`Factorization::set_near`]).
    pub(super) near: bool,
}

impl BlockTriangular {
    /// `unsymmetric`: the mechanics block is (friction), and is factorised by LU.
    pub(super) fn new(
        p: &Pattern,
        s: &Structure,
        unsymmetric: bool,
    ) -> Result<BlockTriangular, LinearError> {
        let mech: Vec<usize> = (0..p.n).filter(|&e| !s.thermal[e]).collect();
        let heat: Vec<usize> = (0..p.n).filter(|&e| s.thermal[e]).collect();
        let block = |eqs: &[usize]| -> Result<Option<SymFactor>, LinearError> {
            if eqs.is_empty() {
                return Ok(None);
            }
            let sub = SubMatrix::new(p, eqs, eqs);
            SymFactor::new(sub, &nodes_of(s, eqs), Precision::Single).map(Some)
        };
        let fm = if unsymmetric && !mech.is_empty() {
            let sub = SubMatrix::new(p, &mech, &mech);
            Some(MechanicsFactor::Lu(Box::new(LaggedLu::new(
                sub,
                &nodes_of(s, &mech),
            ))))
        } else {
            block(&mech)?.map(|f| MechanicsFactor::Ldlt(Box::new(f)))
        };
        let ft = block(&heat)?;
        let lag = Lag::priced(block_lag_price(fm.as_ref(), ft.as_ref(), p));
        Ok(BlockTriangular {
            fm,
            ft,
            coupling: SubMatrix::new(p, &heat, &mech),
            coupling_mt: SubMatrix::new(p, &mech, &heat),
            mech,
            heat,
            lag,
            near: false,
        })
    }

    /// Factorise both diagonal blocks with the current values (the temperature block on the
    /// other core while the mechanics block factors).
    pub(super) fn refactor(&mut self) -> Result<(), LinearError> {
        self.lag.factoring();
        let mech =
            |f: &mut Option<MechanicsFactor>| f.as_mut().map_or(Ok(()), |f| f.factor_current());
        let heat = |f: &mut Option<SymFactor>| f.as_mut().map_or(Ok(()), |f| f.factor_current());
        let (m, t) = rayon::join(|| mech(&mut self.fm), || heat(&mut self.ft));
        m.and(t)?;
        self.lag.factored_now();
        Ok(())
    }

    /// Take the whole system's `values` into the blocks.
    pub(super) fn update(&mut self, values: &[f64]) {
        if let Some(f) = &mut self.fm {
            f.update(values);
        }
        if let Some(f) = &mut self.ft {
            f.sub.update(values);
        }
        self.coupling.update(values);
        self.coupling_mt.update(values);
    }

    /// y = K x by blocks: y_m = K_mm x_m + K_mθ x_θ, y_θ = K_θm x_m + K_θθ x_θ.
    pub(super) fn mul(&self, x: &[f64], y: &mut [f64]) {
        let xm: Vec<f64> = self.mech.iter().map(|&e| x[e]).collect();
        let xt: Vec<f64> = self.heat.iter().map(|&e| x[e]).collect();
        let mut ym = vec![0.0; xm.len()];
        let mut yt = vec![0.0; xt.len()];
        if let Some(f) = &self.fm {
            f.matrix().mul_sub(&xm, &mut ym);
        }
        self.coupling_mt.mul_sub(&xt, &mut ym);
        self.coupling.mul_sub(&xm, &mut yt);
        if let Some(f) = &self.ft {
            f.sub.mul_sub(&xt, &mut yt);
        }
        for (&e, v) in self.mech.iter().zip(&ym) {
            y[e] = -*v;
        }
        for (&e, v) in self.heat.iter().zip(&yt) {
            y[e] = -*v;
        }
    }

    /// z = P⁻¹ r: z_m = K_mm⁻¹ r_m, z_θ = K_θθ⁻¹ (r_θ − K_θm z_m).
    pub(super) fn precondition(&self, r: &[f64], z: &mut [f64]) {
        let mut zm: Vec<f64> = self.mech.iter().map(|&e| r[e]).collect();
        if let Some(f) = &self.fm {
            f.solve(&mut zm);
        }
        let mut zt: Vec<f64> = self.heat.iter().map(|&e| r[e]).collect();
        if let Some(f) = &self.ft {
            self.coupling.mul_sub(&zm, &mut zt);
            f.solve(&mut zt);
        }
        for (&e, v) in self.mech.iter().zip(&zm) {
            z[e] = *v;
        }
        for (&e, v) in self.heat.iter().zip(&zt) {
            z[e] = *v;
        }
    }
}
