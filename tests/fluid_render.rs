//! Drawing a fluid frame against an f64 reference: every pixel centre located in the mesh
//! (barycentric coordinates, grid hash) must show its cell's index and speed; every particle
//! must show at the pixel under its centre.
#![allow(clippy::needless_range_loop)]

mod common;

use std::path::Path;

use galerkin::fluid::gpu::GpuParticles;
use galerkin::fluid::particles::{barycentric, seed_particles, GridHash};
use galerkin::fluid::render::{cell_speeds, draw_picture, DrawStyle, Projection, View2d};
use galerkin::fluid::scene::FluidScene;
use galerkin::fluid::FluidSolver;
use galerkin::render::Colormap;

#[test]
fn every_pixel_shows_the_cell_under_its_centre_and_particles_show_where_they_are() {
    let gpu = common::gpu();
    let scene = FluidScene::load(Path::new("scenes/fluid/tunnel_small.toml")).expect("scene");
    let (mesh, topo) = (&scene.mesh, &scene.topology);
    let mut solver = FluidSolver::new(mesh.clone(), topo.clone(), scene.params).expect("solver");
    let mut state = solver.initial_state(mesh.g().to_vec(), &scene.initial_velocity).expect("start");
    for frame in 1..=3 {
        state = solver.step(&state, mesh.g(), frame).expect("step").0;
    }
    let speeds = cell_speeds(mesh, topo, &state.g, &state.f);
    let size = (400, 130);
    let (lo, hi) = mesh.bounds();
    let view = View2d::fit([lo[0], lo[1]], [hi[0], hi[1]], size, 0.02);
    let style = DrawStyle {
        colormap: Colormap::viridis(),
        range: (0.0, 2.0),
        log: false,
        colour_cells: true,
        sprite_px: 2.0,
    };
    let picture =
        draw_picture(&gpu, (mesh, topo), &state.g, &speeds, None, &style, &Projection::Plane(view), size)
            .expect("draw");
    let grid = GridHash::new(mesh, &[&state.g]);
    let (mut checked, mut ambiguous, mut background) = (0, 0, 0);
    let pixel = (view.hi[0] - view.lo[0]) / f64::from(size.0);
    for py in 0..size.1 {
        for px in 0..size.0 {
            let [x, y] = view.pixel_centre(px, py, size);
            let i = 4 * (py * size.0 + px) as usize;
            let (value, cell) = (picture.raw[i], picture.raw[i + 1]);
            let mut owner = None;
            let mut near_edge = false;
            for &c in grid.candidates(grid.bucket([x, y, 0.0])) {
                let p = mesh.cell_points_at(&state.g, c as usize);
                let b = barycentric(2, &p, [x, y, 0.0]);
                let area = galerkin::mesh::geometry::signed_volume(2, &p);
                for k in 0..3 {
                    // Distance to edge k in pixels. Within 1/64 px of an edge the rasteriser
                    // decides by vertices snapped to its sub-pixel grid (8 bits on lavapipe:
                    // 1/256 px) and its tie rule: not checked.
                    let edge = galerkin::mesh::geometry::face_area_normal(2, &p, k);
                    let len = (edge[0] * edge[0] + edge[1] * edge[1]).sqrt();
                    if (b[k] * 2.0 * area / len / pixel).abs() < 1.0 / 64.0 {
                        near_edge = true;
                    }
                }
                if b[..3].iter().all(|&v| v >= 0.0) {
                    owner = Some(c as usize);
                }
            }
            if near_edge {
                ambiguous += 1;
                continue;
            }
            match owner {
                None => {
                    background += 1;
                    assert_eq!(cell, -1.0, "pixel ({px}, {py}) at ({x:.4}, {y:.4}) is outside the fluid");
                }
                Some(c) => {
                    checked += 1;
                    assert_eq!(
                        cell, c as f32,
                        "pixel ({px}, {py}) at ({x:.4}, {y:.4}) shows cell {cell}, not {c}"
                    );
                    assert_eq!(value, speeds[c] as f32, "pixel ({px}, {py}): speed");
                }
            }
        }
    }
    eprintln!("{checked} fluid pixels, {background} background (obstacle and margin), {ambiguous} on edges");
    // Cells here are ~4 px across: a band of ±1/64 px around every edge is ~3 % of the area.
    assert!(ambiguous * 100 < 5 * checked, "fewer than 5 % of pixels sit on edges");
    // The colour target: each fluid pixel's colour is its speed on the ramp, to 1/255.
    let mut colour_checked = 0;
    for py in (0..size.1).step_by(7) {
        for px in (0..size.0).step_by(7) {
            let i = 4 * (py * size.0 + px) as usize;
            if picture.raw[i + 1] < 0.0 {
                continue;
            }
            let t = galerkin::render::ramp_coordinate(f64::from(picture.raw[i]), 0.0, 2.0, false);
            let want = style.colormap.sample(t);
            for k in 0..3 {
                let got = f64::from(picture.rgba[i + k]) / 255.0;
                // The ramp texture and the target are both UNORM: one rounding each, 1.5/255.
                assert!(
                    (got - want[k]).abs() <= 1.5 / 255.0,
                    "pixel ({px}, {py}) channel {k}: {got} vs ramp {}",
                    want[k]
                );
            }
            colour_checked += 1;
        }
    }
    assert!(colour_checked > 500);

    // Particles, drawn without cells: the pixel under each particle's centre shows a particle
    // of the same cell (sprites may overlap; another particle there must be near).
    let particles = seed_particles(mesh, 300);
    let device = GpuParticles::new(&gpu, mesh, topo, &particles).expect("particles");
    let only = DrawStyle { colour_cells: false, ..style.clone() };
    let picture = draw_picture(
        &gpu,
        (mesh, topo),
        &state.g,
        &speeds,
        Some(&device),
        &only,
        &Projection::Plane(view),
        size,
    )
    .expect("draw");
    let mut shown = 0;
    for p in &particles {
        let [sx, sy] = view.project([p.position[0], p.position[1]], size);
        let (px, py) = (sx.floor() as u32, sy.floor() as u32);
        let i = 4 * (py * size.0 + px) as usize;
        assert_eq!(picture.raw[i + 2], 1.0, "a particle covers pixel ({px}, {py})");
        if picture.raw[i + 1] == p.cell as f32 {
            shown += 1;
            assert_eq!(picture.raw[i], speeds[p.cell as usize] as f32);
        }
    }
    eprintln!("{shown} of {} particles show their own cell at their centre pixel", particles.len());
    assert!(shown * 10 >= particles.len() * 9, "later sprites may cover a few: at least 90 % visible");

    // A sprite is the disc of radius sprite_px about its particle: around a particle with no
    // other within reach, pixel centres nearer than the radius less 0.75 px show the particle,
    // those from the radius plus 0.75 px to 3 px beyond do not (0.75: the disc's edge crosses a
    // pixel's centre within half a pixel's diagonal of it, and f32 positions move it by far less).
    let r = only.sprite_px;
    let screen: Vec<[f64; 2]> =
        particles.iter().map(|p| view.project([p.position[0], p.position[1]], size)).collect();
    let (mut inside, mut outside) = (0, 0);
    for (k, c) in screen.iter().enumerate() {
        let near = |q: &[f64; 2]| ((q[0] - c[0]).powi(2) + (q[1] - c[1]).powi(2)).sqrt() < 2.0 * r + 4.0;
        if screen.iter().enumerate().any(|(j, q)| j != k && near(q)) {
            continue;
        }
        let (x0, y0) = ((c[0] - r - 3.0).floor() as i64, (c[1] - r - 3.0).floor() as i64);
        for py in y0..=y0 + (2.0 * r + 6.0) as i64 {
            for px in x0..=x0 + (2.0 * r + 6.0) as i64 {
                if px < 0 || py < 0 || px >= i64::from(size.0) || py >= i64::from(size.1) {
                    continue;
                }
                let d = ((px as f64 + 0.5 - c[0]).powi(2) + (py as f64 + 0.5 - c[1]).powi(2)).sqrt();
                let covered = picture.raw[4 * (py as usize * size.0 as usize + px as usize) + 2] == 1.0;
                if d < r - 0.75 {
                    assert!(covered, "pixel ({px}, {py}) {d:.2} px from particle {k}: inside its sprite");
                    inside += 1;
                } else if d > r + 0.75 && d < r + 3.0 {
                    assert!(!covered, "pixel ({px}, {py}) {d:.2} px from particle {k}: outside its sprite");
                    outside += 1;
                }
            }
        }
    }
    eprintln!("sprite discs: {inside} pixels inside, {outside} outside checked");
    assert!(inside > 100 && outside > 1000);
}

#[test]
fn a_3d_frame_shows_the_far_walls_and_the_particles_in_front_of_them() {
    let gpu = common::gpu();
    let scene = FluidScene::load(Path::new("scenes/fluid/cavity_small.toml")).expect("scene");
    let (mesh, topo) = (&scene.mesh, &scene.topology);
    let mut solver = FluidSolver::new(mesh.clone(), topo.clone(), scene.params).expect("solver");
    let state = solver.initial_state(mesh.g().to_vec(), &scene.initial_velocity).expect("start");
    let speeds = cell_speeds(mesh, topo, &state.g, &state.f);
    let particles = seed_particles(mesh, 400);
    let device = GpuParticles::new(&gpu, mesh, topo, &particles).expect("particles");
    let (lo, hi) = mesh.bounds();
    let camera = galerkin::render::camera_for_box(lo, hi);
    let size = (320, 240);
    let style = DrawStyle {
        colormap: Colormap::viridis(),
        range: (0.0, 1.0),
        log: false,
        colour_cells: false,
        sprite_px: 1.5,
    };
    let picture = draw_picture(
        &gpu,
        (mesh, topo),
        &state.g,
        &speeds,
        Some(&device),
        &style,
        &Projection::Perspective(camera),
        size,
    )
    .expect("draw");
    let walls = picture.raw.chunks_exact(4).filter(|p| p[2] == 2.0).count();
    assert!(walls > 2000, "the far walls cover the cavity's silhouette ({walls} pixels)");
    let mut shown = 0;
    let mut missing = Vec::new();
    for p in &particles {
        let (sx, sy) = camera.project(glam::DVec3::from_array(p.position), size.0, size.1);
        let (px, py) = (sx.floor() as u32, sy.floor() as u32);
        let i = 4 * (py * size.0 + px) as usize;
        if picture.raw[i + 2] != 1.0 {
            missing.push((p.position, sx, sy));
            continue;
        }

        shown += usize::from(picture.raw[i + 1] == p.cell as f32);
    }
    eprintln!(
        "3D: {} of {} particle centres hidden, {shown} show their own cell",
        missing.len(),
        particles.len()
    );
    // Depth-tested: a particle behind a far wall that is nearer the eye (the central cavity's
    // back wall in front of a small cavity seen through it) is hidden by that wall; the
    // pixel then shows the wall. The rest are drawn.
    for &(position, sx, sy) in &missing {
        let i = 4 * (sy.floor() as u32 * size.0 + sx.floor() as u32) as usize;
        assert_eq!(picture.raw[i + 2], 2.0, "particle at {position:?} neither drawn nor behind a wall");
    }
    assert!(
        missing.len() * 10 <= particles.len(),
        "{} of {} particles hidden",
        missing.len(),
        particles.len()
    );
    // In 3D particles at different depths project onto each other: most, not all, show their
    // own cell.
    assert!(
        shown * 10 >= particles.len() * 6,
        "{shown} of {} particles show their own cell",
        particles.len()
    );
}
