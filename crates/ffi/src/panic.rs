//! What a panic does on a bare-metal target: call the application's `tcomp_panic_hook` with the
//! place in tcomp's source, then stop.
//!
//! Why a hook the application must define: only the application knows how to report (a fault
//! record in no-init RAM, a UART line, a debugger breakpoint) and how to stop (a reset through its
//! watchdog). The library cannot pick one for it, and a library that silently spins would hide a
//! bug. No panic is expected — the core never panics on data, and `tests/no_panic.rs` drives every
//! entry point with arbitrary bytes — but the code paths that *could* panic (an index the
//! optimiser could not prove in bounds) are compiled in, so the handler must exist. If the hook
//! returns, the handler spins until the application's watchdog resets the part.
//!
//! On the host nothing here is compiled: std's handler runs, and `guard.rs` catches the unwind.
#![allow(unsafe_code)] // declaring and calling the application's hook

#[cfg(all(target_os = "none", not(test)))]
unsafe extern "C" {
    /// Defined by the application (see `tcomp.h`): `file` (not NUL-terminated, `file_len`
    /// bytes) and `line` of the panic in tcomp's sources.
    fn tcomp_panic_hook(file: *const u8, file_len: usize, line: u32);
}

#[cfg(all(target_os = "none", not(test)))]
#[panic_handler]
fn panic(info: &core::panic::PanicInfo<'_>) -> ! {
    let (file, line) = info.location().map_or(("", 0), |l| (l.file(), l.line()));
    // SAFETY: the application defines the hook with this signature (the header declares it);
    // the pointer and length describe a string in static storage.
    unsafe { tcomp_panic_hook(file.as_ptr(), file.len(), line) };
    loop {
        core::hint::spin_loop();
    }
}
