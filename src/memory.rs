//! How this process's allocator keeps the memory it frees. A run whose medium is made again
//! drops and builds its structures anew at every remake (the solver's pattern and factor
//! layout, the assembler's maps, the state carried over), blocks of tens of kilobytes to a few
//! megabytes. glibc's malloc by default takes each block above its threshold from the system
//! as fresh pages and gives it back when freed, and gives back the free top of its heap, so
//! that every remake pays a page fault for each page it touches again: on the square pad in
//! 3D with friction the static LU's layout took 31 ms a remake, 13 ms with the freed pages kept
//! (docs/notes/2026-12-07-freed-memory-kept-for-the-next-remake.md). Such a run keeps them.

/// The largest block glibc lets come from its heap rather than from pages of its own (its
/// limit for `M_MMAP_THRESHOLD` on 64-bit systems, 32 MiB): the factors of large systems are
/// still given back whole when freed.
const FROM_HEAP: i32 = 32 << 20;

/// Keep what is freed for what is allocated next: blocks up to [`FROM_HEAP`] from the heap,
/// and the heap's free top kept. Process-wide, for the rest of the run; true where the
/// allocator took both settings (glibc), false elsewhere.
pub fn keep_freed_for_reuse() -> bool {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: mallopt only sets two of the allocator's parameters; any value is accepted
        // or refused (returning 0), never undefined
        unsafe {
            libc::mallopt(libc::M_MMAP_THRESHOLD, FROM_HEAP) == 1
                && libc::mallopt(libc::M_TRIM_THRESHOLD, i32::MAX) == 1
        }
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    {
        false
    }
}

#[cfg(all(test, target_os = "linux", target_env = "gnu"))]
mod tests {
    use super::*;

    /// Page faults of the calling thread so far (minor: pages mapped, none read from disk).
    fn faults() -> i64 {
        let mut usage = std::mem::MaybeUninit::<libc::rusage>::zeroed();
        // SAFETY: a valid pointer to a rusage the call fills
        let ok = unsafe { libc::getrusage(libc::RUSAGE_THREAD, usage.as_mut_ptr()) } == 0;
        assert!(ok);
        // SAFETY: filled by the successful call above
        unsafe { usage.assume_init() }.ru_minflt
    }

    /// Page faults while a block of 8 MiB is allocated and written, after one like it was.
    fn faults_of_a_block_again() -> i64 {
        let touch = |mut v: Vec<u8>| {
            for k in (0..v.len()).step_by(4096) {
                v[k] = 1;
            }
            std::hint::black_box(&v);
        };
        touch(vec![0u8; 8 << 20]);
        let before = faults();
        touch(vec![0u8; 8 << 20]);
        faults() - before
    }

    #[test]
    fn a_block_freed_is_used_again_without_new_pages() {
        // SAFETY: sysconf reads a constant of the system
        let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) }.max(1);
        let pages = (8 << 20) / page;
        // glibc's defaults, fixed (not moved by what was freed before): a block of 8 MiB is
        // fresh pages each time (2048 of 4 KiB)
        // SAFETY: as in keep_freed_for_reuse
        unsafe {
            libc::mallopt(libc::M_MMAP_THRESHOLD, 128 << 10);
            libc::mallopt(libc::M_TRIM_THRESHOLD, 128 << 10);
        }
        let by_default = faults_of_a_block_again();
        assert!(keep_freed_for_reuse());
        let kept = faults_of_a_block_again();
        assert!(
            by_default > pages / 2 && kept < pages / 20,
            "{by_default} page faults by default, {kept} with the freed memory kept, of {pages}"
        );
    }
}
