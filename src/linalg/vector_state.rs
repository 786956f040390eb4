//! The upper halves of the vector registers, cleared after faer's dense kernels.
//!
//! faer's dense LU, triangular solves and SVD run hand-written AVX-512 kernels
//! (`private-gemm-x86`) that return with the upper bits of the `zmm` registers still
//! set. On Intel cores every *non-VEX* SSE instruction executed afterwards on that
//! thread then carries a false dependency on those bits (Intel optimisation manual,
//! "Mixing AVX code with SSE code"), and this crate is compiled for baseline x86-64
//! (SSE2), as are glibc's `exp` and `hypot` wrappers: after the multigrid's coarsest
//! dense LU the rayon workers evaluated `exp` many times slower, and the gradient
//! shapes made after the solve slowed down with it
//! (docs/notebook/2026-11-26-up-form-iterative-solvers.md, "The vector registers'
//! upper halves"). `vzeroupper` ends that state; it costs about a cycle.
//!
//! Call [`clear_upper_halves`] on the thread that ran a faer kernel, and
//! [`clear_upper_halves_everywhere`] after a call that may have run on the rayon pool.

/// `vzeroupper` on the current thread when the CPU has AVX (nothing elsewhere):
/// zeroes bits 128 and above of vector registers 0-15.
#[inline]
pub fn clear_upper_halves() {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: `vzeroupper` exists on every CPU with AVX (checked above), touches no
        // memory, the stack or the flags, and only changes vector registers, which
        // `clobber_abi("C")` declares overwritten, so no live value is held in them.
        unsafe { std::arch::asm!("vzeroupper", clobber_abi("C"), options(nomem, nostack, preserves_flags)) };
    }
}

/// [`clear_upper_halves`] on every thread of the rayon pool and on the calling thread.
pub fn clear_upper_halves_everywhere() {
    rayon::broadcast(|_| clear_upper_halves());
    clear_upper_halves();
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The clearing is callable from any thread and leaves floating-point values held
    /// across it intact (`clobber_abi` keeps the compiler from holding them in vector
    /// registers across the instruction).
    #[test]
    fn values_survive_the_clearing() {
        let x: Vec<f64> = (0..64).map(|i| (i as f64).sqrt()).collect();
        let before: f64 = x.iter().sum();
        clear_upper_halves();
        clear_upper_halves_everywhere();
        let after: f64 = x.iter().sum();
        assert_eq!(before, after);
        assert_eq!(std::hint::black_box(2.5f64).exp(), 2.5f64.exp());
    }
}
