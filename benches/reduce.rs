//! `cargo bench --bench reduce [-- --quick]`: the reduction core's report (the same tables as
//! `galerkin bench reduce`).

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let gpu = galerkin::gpu::Gpu::new(&galerkin::gpu::GpuDesc::from_env()).ok();
    let mut emit = |section: &str| print!("{section}");
    if let Err(e) = galerkin::bench::reduce::report(quick, gpu.as_ref(), None, &mut emit) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
