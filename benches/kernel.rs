//! Time of one cell's residual and tangent (`kernel::bulk`), single-threaded, for each linear
//! element with the physics the scenes give it: the number behind "assembly per Newton
//! iteration per element" once the scatter and the threads are taken away. Where the cell can
//! take it, also the lane kernel (`kernel::lanes`, four cells per call), per cell.

use std::hint::black_box;
use std::time::Instant;
use tmc::dofs::{CellState, Layout};
use tmc::element::{Hex8, Hex27, Quad4, RefElement, Tet4, Tri3};
use tmc::kernel::{Active, CellMaterial, bulk, lanes};
use tmc::material::{Conductivity, MooneyRivlin, Regularization, SolidLaw, ThermoElastic};

const SOLID: CellMaterial = CellMaterial {
    law: SolidLaw::NeoHooke(ThermoElastic {
        K: 20.0,
        mu: 10.0,
        alpha: 1e-5,
        theta0: 0.0,
    }),
    cond: Conductivity::Constant(10.0),
    medium: false,
    reg: None,
    reg_direct: None,
};

/// A law without the coefficient form: the lanes contract its full ∂P/∂F.
const RUBBER: CellMaterial = CellMaterial {
    law: SolidLaw::MooneyRivlin(MooneyRivlin {
        C10: 3.0,
        C01: 2.0,
        K: 20.0,
        alpha: 1e-5,
        theta0: 0.0,
    }),
    ..SOLID
};

const MEDIUM: CellMaterial = CellMaterial {
    law: SolidLaw::NeoHooke(ThermoElastic {
        K: 2e-4,
        mu: 1e-4,
        alpha: 1e-5,
        theta0: 0.0,
    }),
    cond: Conductivity::Medium {
        k_tm: 0.1,
        k_max: 10.0,
    },
    medium: true,
    reg: Some(Regularization {
        beta1: 1.0,
        beta2: 1e-2,
        d: 0.05,
        volume_power: 0,
    }),
    reg_direct: None,
};

/// Microseconds per cell of `bulk` with the tangent, on a distorted, deformed, heated cell,
/// and of the lane kernel where the cell can take it.
fn time<const N: usize, const D: usize, E: RefElement<N, D>>(
    mat: &CellMaterial,
    has_theta: bool,
) -> (f64, Option<f64>) {
    let np = if mat.reg.is_some() {
        D * (D - 1) / 2
    } else {
        0
    };
    let mut s = CellState::<N>::zero();
    for (a, xi) in E::nodes().iter().enumerate() {
        for (d, x) in xi.iter().enumerate() {
            s.X[a][d] = 0.5 * x + 0.05 * ((a * 7 + d * 3) % 5) as f64 / 5.0;
            s.u[a][d] = 0.03 * (((a * 3 + d * 5) % 7) as f64 / 7.0 - 0.5);
        }
        s.theta[a] = 10.0 * (a % 3) as f64;
    }
    let lay = Layout {
        n: N,
        dim: D,
        has_u: true,
        has_theta,
        np,
    };
    let nd = lay.ndof();
    let (mut r, mut k) = (vec![0.0; lanes::W * nd], vec![0.0; lanes::W * nd * nd]);
    // TMC_KERNEL_CALLS=n: exactly n calls (for instruction counts under callgrind)
    let fixed: Option<usize> = std::env::var("TMC_KERNEL_CALLS")
        .ok()
        .and_then(|v| v.parse().ok());
    let repeat = |call: &mut dyn FnMut()| {
        let mut calls = 0;
        let t0 = Instant::now();
        while match fixed {
            Some(n) => calls < n,
            None => calls < 2000 || t0.elapsed().as_secs_f64() < 0.5,
        } {
            call();
            calls += 1;
        }
        t0.elapsed().as_secs_f64() / calls as f64 * 1e6
    };
    let one = repeat(&mut || {
        bulk::<N, D, E>(mat, &lay, black_box(&s), Active::ALL, &mut r, Some(&mut k)).unwrap();
        black_box(&k);
    });
    let four = [s; lanes::W];
    let block = lanes::LaneBlock::new(mat, &lay, Active::ALL).filter(|_| lanes::available());
    let lanes = block.map(|b| {
        repeat(&mut || {
            lanes::bulk_lanes::<N, D, E>(&b, black_box(&four), &mut r, Some(&mut k)).unwrap();
            black_box(&k);
        }) / lanes::W as f64
    });
    (one, lanes)
}

type Row = (
    &'static str,
    &'static str,
    usize,
    fn() -> (f64, Option<f64>),
);

fn main() {
    println!("\nkernel::bulk, residual + tangent of one cell, one thread (µs per cell)\n");
    println!("| element | physics | dofs | µs | lanes µs |");
    println!("|---|---|---:|---:|---:|");
    let rows: [Row; 11] = [
        ("T1", "solid u", 6, || time::<3, 2, Tri3>(&SOLID, false)),
        ("Q1", "solid u, θ", 12, || {
            time::<4, 2, Quad4>(&SOLID, true)
        }),
        ("Q1", "medium u, θ, p", 16, || {
            time::<4, 2, Quad4>(&MEDIUM, true)
        }),
        ("tet4", "solid u, θ", 16, || {
            time::<4, 3, Tet4>(&SOLID, true)
        }),
        ("H1", "solid u", 24, || time::<8, 3, Hex8>(&SOLID, false)),
        ("H1", "solid u, θ", 32, || time::<8, 3, Hex8>(&SOLID, true)),
        ("H1", "Mooney-Rivlin solid u, θ", 32, || {
            time::<8, 3, Hex8>(&RUBBER, true)
        }),
        ("H1", "medium u, θ", 32, || {
            time::<8, 3, Hex8>(&MEDIUM_NO_P, true)
        }),
        ("H1", "medium u, θ, p", 56, || {
            time::<8, 3, Hex8>(&MEDIUM, true)
        }),
        ("H2", "solid u, θ", 108, || {
            time::<27, 3, Hex27>(&SOLID, true)
        }),
        ("H2", "medium u, θ, direct regularization", 108, || {
            time::<27, 3, Hex27>(&MEDIUM_DIRECT, true)
        }),
    ];
    // TMC_KERNEL_ONLY="H1 solid u, θ": that row only
    let only = std::env::var("TMC_KERNEL_ONLY").ok();
    for (e, what, nd, f) in rows {
        if only.as_ref().is_some_and(|o| *o != format!("{e} {what}")) {
            continue;
        }
        let (one, lanes) = f();
        let lanes = lanes.map_or("-".into(), |t| format!("{t:.2}"));
        println!("| {e} | {what} | {nd} | {one:.2} | {lanes} |");
    }
}

const MEDIUM_NO_P: CellMaterial = CellMaterial {
    reg: None,
    ..MEDIUM
};

/// A quadratic medium cell: the direct regularization of eq. 18, weight γ α_r.
const MEDIUM_DIRECT: CellMaterial = CellMaterial {
    reg: None,
    reg_direct: Some(1e-4),
    ..MEDIUM
};
