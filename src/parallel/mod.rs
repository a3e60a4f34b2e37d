//! The processes of a run: one, or several started by `mpirun`, each a rank of MPI's world.
//! [`Ranks`] is what the layers above see: which rank this is, how many there are, and the
//! collective operations that keep every rank's decisions identical (sums, minima,
//! broadcasts). Without the `petsc` feature, or outside `mpirun`, there is one rank and the
//! collectives do nothing.
//!
//! With the `petsc` feature, [`petsc`] starts and ends the engine (MPI, then PETSc) and wraps
//! the few PETSc objects tmc uses, declared in [`ffi`] against the installed headers.

#[cfg(feature = "petsc")]
pub mod ffi;
#[cfg(feature = "petsc")]
pub mod petsc;

/// Why a run cannot use PETSc in a build without it.
pub const NOT_BUILT: &str = "this tmc was built without the PETSc engine (needed for several \
    ranks and for engine = \"petsc\"): build it with `cargo build --release --features petsc` \
    (make build does) after `make deps`";

/// This process's rank among `size`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ranks {
    pub rank: usize,
    pub size: usize,
}

/// Which rank owns each cell, boundary facet and node of a mesh (`mesh::partition` cuts it).
#[derive(Clone, Debug, PartialEq)]
pub struct Partition {
    pub parts: usize,
    /// Per cell block of the mesh, the rank of each cell.
    pub cell_rank: Vec<Vec<u32>>,
    /// Per facet block of the mesh, the rank of each facet.
    pub facet_rank: Vec<Vec<u32>>,
    /// The rank of each node.
    pub node_rank: Vec<u32>,
}

impl Partition {
    /// Cells per rank.
    pub fn cells_per_rank(&self) -> Vec<usize> {
        let mut n = vec![0; self.parts];
        for r in self.cell_rank.iter().flatten() {
            n[*r as usize] += 1;
        }
        n
    }
}

/// How a distributed run is spread: its ranks and which of them owns what. Made once when
/// the run is planned, and handed to the assembler (the cells a rank assembles), the engine
/// (the rows a rank holds) and the output (the part of each step a rank writes).
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution {
    pub ranks: Ranks,
    pub partition: Partition,
}

impl Distribution {
    /// Whether this rank owns cell `c` of mesh cell block `block`.
    pub fn owns_cell(&self, block: usize, c: usize) -> bool {
        self.partition.cell_rank[block][c] as usize == self.ranks.rank
    }

    /// Whether this rank owns node `n` (and the rows of its equations).
    pub fn owns_node(&self, n: usize) -> bool {
        self.partition.node_rank[n] as usize == self.ranks.rank
    }

    /// Per cell, the cell blocks one after another: whether this rank owns it.
    pub fn my_cells(&self) -> Vec<bool> {
        let me = self.ranks.rank as u32;
        self.partition
            .cell_rank
            .iter()
            .flatten()
            .map(|&r| r == me)
            .collect()
    }
}

/// The number of processes `mpirun` (Open MPI, or a PMI launcher) started this one among,
/// read from the environment it sets; `None` when not started by a launcher.
pub fn launched_size() -> Option<usize> {
    launcher_number(["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"])
}

/// This process's rank as `mpirun` set it in the environment (before MPI is started).
pub fn launched_rank() -> Option<usize> {
    launcher_number(["OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"])
}

/// The first of the launchers' variables `keys` that is set, as a number.
fn launcher_number(keys: [&str; 3]) -> Option<usize> {
    keys.iter()
        .find_map(|k| std::env::var(k).ok()?.trim().parse().ok())
}

impl Ranks {
    /// One process.
    pub const SERIAL: Ranks = Ranks { rank: 0, size: 1 };

    /// MPI's world once the engine is started, else one process.
    pub fn world() -> Ranks {
        #[cfg(feature = "petsc")]
        if let Some(r) = petsc::world() {
            return r;
        }
        Ranks::SERIAL
    }

    /// The rank that writes the run's files and prints its progress.
    pub fn is_root(&self) -> bool {
        self.rank == 0
    }

    pub fn is_serial(&self) -> bool {
        self.size == 1
    }

    /// Every entry summed over the ranks, on every rank.
    pub fn sum_into(&self, v: &mut [f64]) {
        #[cfg(feature = "petsc")]
        if !self.is_serial() && !v.is_empty() {
            petsc::all_reduce(v, petsc::Reduce::Sum);
        }
        #[cfg(not(feature = "petsc"))]
        let _ = v;
    }

    /// The sum of `x` over the ranks.
    pub fn sum(&self, x: f64) -> f64 {
        let mut v = [x];
        self.sum_into(&mut v);
        v[0]
    }

    /// The least of `x` over the ranks.
    pub fn min(&self, x: f64) -> f64 {
        #[cfg(feature = "petsc")]
        if !self.is_serial() {
            let mut v = [x];
            petsc::all_reduce(&mut v, petsc::Reduce::Min);
            return v[0];
        }
        x
    }

    /// The greatest of `x` over the ranks.
    pub fn max(&self, x: f64) -> f64 {
        -self.min(-x)
    }

    /// `bytes` of rank `root` on every rank.
    #[allow(clippy::ptr_arg)]
    pub fn broadcast(&self, root: usize, bytes: &mut Vec<u8>) {
        #[cfg(feature = "petsc")]
        if !self.is_serial() {
            petsc::broadcast(root, bytes);
        }
        #[cfg(not(feature = "petsc"))]
        let _ = (root, bytes);
    }

    /// Every rank's `Err` or `Ok` made one: the error of the lowest failing rank (sent as
    /// text by `encode`, read back by `decode`) on every rank, or `Ok` on every rank.
    pub fn agree<T, E>(
        &self,
        r: Result<T, E>,
        encode: impl Fn(&E) -> String,
        decode: impl Fn(&str) -> E,
    ) -> Result<T, E> {
        if self.is_serial() {
            return r;
        }
        let mine = if r.is_err() { self.rank } else { self.size };
        let first = self.min(mine as f64) as usize;
        if first == self.size {
            return r;
        }
        let mut bytes = match &r {
            Err(e) if self.rank == first => encode(e).into_bytes(),
            _ => Vec::new(),
        };
        self.broadcast(first, &mut bytes);
        match r {
            Err(e) if self.rank == first => Err(e),
            _ => Err(decode(&String::from_utf8_lossy(&bytes))),
        }
    }
}
