//! `cargo bench --bench gpu [-- --quick]`: the device's ceilings next to their CPU peers (the
//! same table as `galerkin bench gpu`).

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let gpu = match galerkin::gpu::Gpu::new(&galerkin::gpu::GpuDesc::from_env()) {
        Ok(g) => g,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let config =
        if quick { galerkin::bench::BenchConfig::quick() } else { galerkin::bench::BenchConfig::full() };
    match galerkin::bench::run(&gpu, &config, |step| eprintln!("… {step}")) {
        Ok(rows) => {
            let c = gpu.caps();
            println!("device: {} — {}\n", c.device_name, c.driver);
            print!("{}", galerkin::bench::table(&rows));
        }
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}
