//! Restarted, right-preconditioned GMRES.
//!
//! Its vector operations (the Gram–Schmidt products and updates, the norms) run on every
//! thread for a long vector: cut into pieces of [`PIECE`] entries, a task each, a product's
//! piece sums then added in the pieces' order. The cut depends on the length alone, so GMRES
//! takes the same iterations to the last bit on any number of threads; a vector of one piece
//! is summed as on one thread.

use rayon::prelude::*;

/// The entries of a piece of a vector operation.
const PIECE: usize = 1 << 13;

/// a · c.
fn dot(a: &[f64], c: &[f64]) -> f64 {
    let serial = |a: &[f64], c: &[f64]| a.iter().zip(c).map(|(p, q)| p * q).sum::<f64>();
    if a.len() <= PIECE {
        return serial(a, c);
    }
    let parts: Vec<f64> = a
        .par_chunks(PIECE)
        .zip(c.par_chunks(PIECE))
        .map(|(a, c)| serial(a, c))
        .collect();
    parts.iter().sum()
}

/// y ← f(y, x) entry by entry.
fn each(y: &mut [f64], x: &[f64], f: impl Fn(&mut f64, f64) + Sync) {
    if y.len() <= PIECE {
        return y.iter_mut().zip(x).for_each(|(a, &c)| f(a, c));
    }
    y.par_chunks_mut(PIECE)
        .zip(x.par_chunks(PIECE))
        .for_each(|(y, x)| y.iter_mut().zip(x).for_each(|(a, &c)| f(a, c)));
}

/// Restarted GMRES with right preconditioning (A M⁻¹ y = b, x = M⁻¹ y) from the `x` given,
/// modified Gram–Schmidt and Givens rotations, until the residual is `rtol` times |b|.
/// Returns the iterations, or (iterations, relative residual) when `max_it` is reached
/// first, or with `give_up`, as soon as the residual is not on course to reach `rtol` within
/// `max_it` (after a third of them, above `rtol` to the power of a third); `x` holds the
/// last iterate either way.
#[allow(clippy::too_many_arguments)]
pub fn gmres(
    matvec: &dyn Fn(&[f64], &mut [f64]),
    precond: &dyn Fn(&[f64], &mut [f64]),
    b: &[f64],
    x: &mut [f64],
    rtol: f64,
    restart: usize,
    max_it: usize,
    give_up: bool,
) -> Result<usize, (usize, f64)> {
    let n = b.len();
    let bnorm = dot(b, b).sqrt();
    if bnorm == 0.0 {
        x.fill(0.0);
        return Ok(0);
    }
    let mut r = b.to_vec();
    let mut w = vec![0.0; n];
    if x.iter().any(|&v| v != 0.0) {
        matvec(x, &mut w);
        each(&mut r, &w, |a, c| *a -= c);
    }
    let mut its = 0;
    let mut rel = 1.0;
    // where a give-up is decided, and the residual it needs there
    let checkpoint = max_it.div_ceil(3);
    let on_course = rtol.powf(checkpoint as f64 / max_it as f64);
    let mut behind = false;
    while its < max_it && !behind {
        let beta = dot(&r, &r).sqrt();
        rel = beta / bnorm;
        if rel <= rtol {
            return Ok(its);
        }
        let m = restart.min(max_it - its);
        let mut v: Vec<Vec<f64>> = vec![scaled(&r, beta)];
        // M⁻¹ v_k, kept for the update (one application of M⁻¹ fewer per cycle)
        let mut zs: Vec<Vec<f64>> = Vec::new();
        let mut h = vec![vec![0.0; m]; m + 1]; // h[row][col]
        let (mut cs, mut sn) = (vec![0.0; m], vec![0.0; m]);
        let mut g = vec![0.0; m + 1];
        g[0] = beta;
        let mut k = 0;
        while k < m {
            let mut z = vec![0.0; n];
            precond(&v[k], &mut z);
            matvec(&z, &mut w);
            zs.push(z);
            for (i, vi) in v.iter().enumerate() {
                let hik = dot(&w, vi);
                h[i][k] = hik;
                each(&mut w, vi, |a, c| *a -= hik * c);
            }
            let wn = dot(&w, &w).sqrt();
            h[k + 1][k] = wn;
            for i in 0..k {
                let t = cs[i] * h[i][k] + sn[i] * h[i + 1][k];
                h[i + 1][k] = -sn[i] * h[i][k] + cs[i] * h[i + 1][k];
                h[i][k] = t;
            }
            let d = h[k][k].hypot(h[k + 1][k]);
            (cs[k], sn[k]) = if d == 0.0 {
                (1.0, 0.0)
            } else {
                (h[k][k] / d, h[k + 1][k] / d)
            };
            h[k][k] = d;
            h[k + 1][k] = 0.0;
            g[k + 1] = -sn[k] * g[k];
            g[k] *= cs[k];
            k += 1;
            its += 1;
            rel = g[k].abs() / bnorm;
            if rel <= rtol || wn == 0.0 {
                break;
            }
            if give_up && its == checkpoint && rel > on_course {
                behind = true;
                break;
            }
            v.push(scaled(&w, wn));
        }
        // y = H⁻¹ g (upper triangular k × k), x += M⁻¹ V y = Σ y_i M⁻¹ v_i
        let mut y = vec![0.0; k];
        for i in (0..k).rev() {
            let s: f64 = (i + 1..k).map(|j| h[i][j] * y[j]).sum();
            y[i] = (g[i] - s) / h[i][i];
        }
        for (zi, yi) in zs.iter().zip(&y) {
            each(x, zi, |a, c| *a += yi * c);
        }
        // true residual for the restart
        matvec(x, &mut w);
        r.copy_from_slice(b);
        each(&mut r, &w, |a, c| *a -= c);
    }
    let rn = dot(&r, &r).sqrt() / bnorm;
    if rn <= rtol && !behind {
        Ok(its)
    } else {
        Err((its, rel.max(rn)))
    }
}

/// v / s.
fn scaled(v: &[f64], s: f64) -> Vec<f64> {
    let mut out = vec![0.0; v.len()];
    each(&mut out, v, |a, c| *a = c / s);
    out
}
