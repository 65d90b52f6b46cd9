//! Single pictures: silhouettes, orientation, colour, light, blending, errors.

use crate::common::{channel_distance, cuboid, renderer, silhouette};
use carus_render::{
    Bounds, Camera, ColourMap, ContactSheet, Image, Lights, Projection, RenderError, RenderMesh,
    Scene, View, LABEL_STRIP,
};
use glam::Vec3;

const WHITE: [u8; 4] = [255, 255, 255, 255];
const SIZE: u32 = 128;

fn unit_cube(rgb: [f32; 3]) -> RenderMesh {
    let (positions, normals, indices) = cuboid([-0.5; 3], [0.5; 3]);
    RenderMesh::new("unit cube", positions, indices, rgb).with_normals(normals)
}

/// Lights that return every surface's own colour: ambient only.
fn flat_lights() -> Lights {
    let mut lights = Lights::default();
    lights.key.intensity = 0.0;
    lights.fill.intensity = 0.0;
    lights.headlight = 0.0;
    lights.rim = 0.0;
    lights.ambient = 1.0;
    lights
}

/// A camera that fits twice the unit cube, so the cube fills about half the picture.
fn roomy_camera(view: View) -> Camera {
    Camera::standard(
        view,
        &Bounds {
            min: [-1.0; 3],
            max: [1.0; 3],
        },
    )
}

#[test]
fn cube_shows_background_at_corners_and_lit_colour_at_centre() {
    let mut renderer = renderer();
    let scene = Scene::new(vec![unit_cube([0.8, 0.1, 0.1])]);
    let image = renderer
        .render(&scene, &roomy_camera(View::Anterior), SIZE, SIZE)
        .unwrap();
    for (x, y) in [(0, 0), (SIZE - 1, 0), (0, SIZE - 1), (SIZE - 1, SIZE - 1)] {
        assert_eq!(image.pixel(x, y), Some(WHITE), "corner ({x}, {y})");
    }
    let [r, g, b, a] = image.pixel(SIZE / 2, SIZE / 2).unwrap();
    assert_eq!(a, 255);
    assert!(
        r > 80 && r > g + 60 && r > b + 60,
        "centre is not lit red: {:?}",
        [r, g, b]
    );
}

#[test]
fn orthographic_silhouette_matches_the_projection() {
    let mut renderer = renderer();
    let scene = Scene::new(vec![unit_cube([0.3, 0.3, 0.7])]);
    for view in [
        View::Anterior,
        View::Lateral,
        View::Inferior,
        View::Superior,
    ] {
        let camera = roomy_camera(view);
        let image = renderer.render(&scene, &camera, SIZE, SIZE).unwrap();
        let ([x0, x1], [y0, y1]) = silhouette(&image, WHITE).expect("cube drawn");
        // Expected span from the camera's own projection of the cube's corners.
        let projected: Vec<[f32; 2]> = Bounds {
            min: [-0.5; 3],
            max: [0.5; 3],
        }
        .corners()
        .iter()
        .map(|c| camera.project(*c, SIZE, SIZE))
        .collect();
        let min_x = projected.iter().map(|p| p[0]).fold(f32::MAX, f32::min);
        let max_x = projected.iter().map(|p| p[0]).fold(f32::MIN, f32::max);
        let min_y = projected.iter().map(|p| p[1]).fold(f32::MAX, f32::min);
        let max_y = projected.iter().map(|p| p[1]).fold(f32::MIN, f32::max);
        let drawn_w = (x1 + 1 - x0) as f32;
        let drawn_h = (y1 + 1 - y0) as f32;
        assert!(
            (drawn_w - (max_x - min_x)).abs() <= 2.0,
            "{view:?}: width {drawn_w} vs {}",
            max_x - min_x
        );
        assert!(
            (drawn_h - (max_y - min_y)).abs() <= 2.0,
            "{view:?}: height {drawn_h} vs {}",
            max_y - min_y
        );
        assert!(
            (x0 as f32 - min_x).abs() <= 1.5 && (y0 as f32 - min_y).abs() <= 1.5,
            "{view:?}: offset"
        );
    }
}

#[test]
fn asymmetric_mesh_differs_between_anterior_and_lateral_views() {
    let mut renderer = renderer();
    // Wide from side to side (x), thin front to back (y), with a green
    // marker on the mother's right (+x) and a blue one in front (+y).
    let (p, n, i) = cuboid([-0.8, -0.2, -0.5], [0.8, 0.2, 0.5]);
    let body = RenderMesh::new("body", p, i, [0.7, 0.7, 0.7]).with_normals(n);
    let (p, n, i) = cuboid([0.8, -0.1, -0.1], [1.0, 0.1, 0.1]);
    let right_marker = RenderMesh::new("right marker", p, i, [0.0, 0.9, 0.0]).with_normals(n);
    let (p, n, i) = cuboid([-0.1, 0.2, -0.1], [0.1, 0.4, 0.1]);
    let front_marker = RenderMesh::new("front marker", p, i, [0.0, 0.0, 0.9]).with_normals(n);
    let mut scene = Scene::new(vec![body, right_marker, front_marker]);
    scene.lights = flat_lights();
    let camera_for = |view| {
        Camera::standard(
            view,
            &Bounds {
                min: [-1.2; 3],
                max: [1.2; 3],
            },
        )
    };

    let anterior = renderer
        .render(&scene, &camera_for(View::Anterior), SIZE, SIZE)
        .unwrap();
    let lateral = renderer
        .render(&scene, &camera_for(View::Lateral), SIZE, SIZE)
        .unwrap();
    let (ax, ay) = silhouette(&anterior, WHITE).unwrap();
    let (lx, ly) = silhouette(&lateral, WHITE).unwrap();
    let (aw, lw) = ((ax[1] - ax[0]) as f32, (lx[1] - lx[0]) as f32);
    assert!(
        aw > 2.5 * lw,
        "anterior width {aw} should far exceed lateral width {lw}"
    );
    assert!(
        ((ay[1] - ay[0]) as i32 - (ly[1] - ly[0]) as i32).abs() <= 2,
        "same height in both"
    );

    // Anterior view: the mother's right is on the picture's left.
    let green = |image: &Image, x: u32, y: u32| {
        let [r, g, b, _] = image.pixel(x, y).unwrap();
        g > 150 && r < 60 && b < 60
    };
    let right_side = camera_for(View::Anterior).project(Vec3::new(0.9, 0.0, 0.0), SIZE, SIZE);
    assert!(right_side[0] < (SIZE / 2) as f32);
    assert!(
        green(&anterior, right_side[0] as u32, right_side[1] as u32),
        "marker not on the left"
    );
    // Lateral view from the right: the marker faces the camera at the centre,
    // and the front marker is on the picture's right.
    assert!(green(&lateral, SIZE / 2, SIZE / 2));
    let front = camera_for(View::Lateral).project(Vec3::new(0.0, 0.3, 0.0), SIZE, SIZE);
    assert!(front[0] > (SIZE / 2) as f32);
    let [r, g, b, _] = lateral.pixel(front[0] as u32, front[1] as u32).unwrap();
    assert!(
        b > 150 && r < 60 && g < 60,
        "front marker not on the right: {:?}",
        [r, g, b]
    );
}

#[test]
fn flat_colours_come_back_as_the_same_srgb_bytes() {
    let mut renderer = renderer();
    let mut scene = Scene::new(vec![unit_cube([0.2, 0.5, 0.8])]);
    scene.lights = flat_lights();
    scene.background = [0.1, 0.3, 0.2, 1.0];
    let image = renderer
        .render(&scene, &roomy_camera(View::Oblique), SIZE, SIZE)
        .unwrap();
    assert!(
        channel_distance(
            image.pixel(SIZE / 2, SIZE / 2).unwrap(),
            [51, 128, 204, 255]
        ) <= 2
    );
    assert!(channel_distance(image.pixel(0, 0).unwrap(), [26, 77, 51, 255]) <= 1);
}

#[test]
fn sphere_is_brighter_towards_the_key_light() {
    let mut renderer = renderer();
    let scene = Scene::new(vec![RenderMesh::sphere(
        "sphere",
        [0.0; 3],
        0.5,
        [0.9, 0.85, 0.75],
    )]);
    let camera = roomy_camera(View::Anterior);
    let image = renderer.render(&scene, &camera, SIZE, SIZE).unwrap();
    let luma = |p: [f32; 2]| {
        let [r, g, b, _] = image.pixel(p[0] as u32, p[1] as u32).unwrap();
        r as u32 + g as u32 + b as u32
    };
    // The default key light comes from the picture's upper left.
    let (right, up, _) = camera.basis();
    let upper_left = camera.project((-right + up) * 0.2, SIZE, SIZE);
    let lower_right = camera.project((right - up) * 0.2, SIZE, SIZE);
    assert!(
        luma(upper_left) > luma(lower_right) + 60,
        "{} vs {}",
        luma(upper_left),
        luma(lower_right)
    );
}

#[test]
fn back_faces_of_an_open_sheet_are_lit_like_front_faces() {
    let mut renderer = renderer();
    // A square in the x-z plane; seen from the front it faces +y, reversed it faces -y.
    let positions = vec![
        [-0.5, 0.0, -0.5],
        [0.5, 0.0, -0.5],
        [0.5, 0.0, 0.5],
        [-0.5, 0.0, 0.5],
    ];
    let facing_front = vec![0, 2, 1, 0, 3, 2];
    let facing_back = vec![0, 1, 2, 0, 2, 3];
    let camera = roomy_camera(View::Anterior);
    let mut centre = |indices| {
        let scene = Scene::new(vec![RenderMesh::new(
            "sheet",
            positions.clone(),
            indices,
            [0.6, 0.6, 0.9],
        )]);
        renderer
            .render(&scene, &camera, SIZE, SIZE)
            .unwrap()
            .pixel(SIZE / 2, SIZE / 2)
            .unwrap()
    };
    let (front, back) = (centre(facing_front), centre(facing_back));
    assert!(channel_distance(front, back) <= 2, "{front:?} vs {back:?}");
    assert!(front[0] > 60, "sheet is dark: {front:?}");
}

#[test]
fn scalar_field_follows_the_colour_map() {
    let mut renderer = renderer();
    // A sheet facing the anterior camera, scalar rising from the mother's
    // right (picture left) to her left.
    let positions = vec![
        [1.0, 0.0, -1.0],
        [-1.0, 0.0, -1.0],
        [-1.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
    ];
    let scalars = positions.iter().map(|p| (1.0 - p[0]) * 0.5).collect();
    let mesh = RenderMesh::new("sheet", positions, vec![0, 1, 2, 0, 2, 3], [0.5; 3]).with_scalars(
        scalars,
        [0.0, 1.0],
        ColourMap::Viridis,
    );
    let mut scene = Scene::new(vec![mesh]);
    scene.lights = flat_lights();
    let camera = roomy_camera(View::Anterior);
    let image = renderer.render(&scene, &camera, SIZE, SIZE).unwrap();
    for t in [0.1_f32, 0.5, 0.9] {
        let [x, y] = camera.project(Vec3::new(1.0 - 2.0 * t, 0.0, 0.0), SIZE, SIZE);
        let got = image.pixel(x as u32, y as u32).unwrap();
        let want = ColourMap::Viridis.sample(t);
        assert!(
            channel_distance(got, want) <= 6,
            "t = {t}: {got:?} vs {want:?}"
        );
    }
}

#[test]
fn transparent_mesh_blends_over_the_opaque_one_behind_it() {
    let mut renderer = renderer();
    let shell = RenderMesh::sphere("shell", [0.0; 3], 0.9, [0.2, 0.3, 0.9]).with_opacity(0.35);
    let inner = unit_cube([0.9, 0.1, 0.1]);
    let camera = roomy_camera(View::Anterior);
    let centre_of = |meshes: Vec<RenderMesh>, renderer: &mut carus_render::Renderer| {
        let mut scene = Scene::new(meshes);
        scene.lights = flat_lights();
        renderer
            .render(&scene, &camera, SIZE, SIZE)
            .unwrap()
            .pixel(SIZE / 2, SIZE / 2)
            .unwrap()
    };
    let cube_alone = centre_of(vec![inner.clone()], &mut renderer);
    let shell_alone = centre_of(vec![shell.clone()], &mut renderer);
    // Listed before the cube on purpose: drawing order must not depend on it.
    let both = centre_of(vec![shell, inner], &mut renderer);
    // Red cube instead of white background behind the shell: green drops.
    assert!(
        both[1] + 60 < shell_alone[1],
        "cube hidden: {both:?} vs shell {shell_alone:?}"
    );
    assert!(
        both[2] > cube_alone[2] + 30,
        "shell not blended: {both:?} vs cube {cube_alone:?}"
    );
    assert_eq!(both[3], 255);
}

#[test]
fn perspective_camera_draws_nearer_faces_larger() {
    let mut renderer = renderer();
    let scene = Scene::new(vec![unit_cube([0.5, 0.5, 0.5])]);
    let bounds = Bounds {
        min: [-0.5; 3],
        max: [0.5; 3],
    };
    let ortho = Camera::standard(View::Anterior, &bounds);
    let persp = ortho.with_projection(Projection::Perspective { fov_y: 0.8 }, &bounds);
    let near = persp.project(Vec3::new(0.5, 0.5, 0.5), SIZE, SIZE);
    let far = persp.project(Vec3::new(0.5, -0.5, 0.5), SIZE, SIZE);
    assert!((near[0] - SIZE as f32 / 2.0).abs() > (far[0] - SIZE as f32 / 2.0).abs());
    let image = renderer.render(&scene, &persp, SIZE, SIZE).unwrap();
    let ([x0, x1], _) = silhouette(&image, WHITE).unwrap();
    assert!(((x1 + 1 - x0) as f32 - 2.0 * (SIZE as f32 / 2.0 - near[0]).abs()).abs() <= 2.0);
}

#[test]
fn contact_sheet_puts_three_labelled_views_side_by_side() {
    let mut renderer = renderer();
    let scene = Scene::new(vec![unit_cube([0.8, 0.7, 0.5])]);
    let sheet = ContactSheet {
        tile_size: [96, 80],
        gap: 4,
        ..ContactSheet::default()
    };
    let image = renderer.contact_sheet(&scene, &sheet).unwrap();
    assert_eq!(
        (image.width(), image.height()),
        (3 * 96 + 4 * 4, 80 + LABEL_STRIP + 2 * 4)
    );
    for tile in 0..3 {
        let x = 4 + tile * (96 + 4);
        assert_ne!(
            image.pixel(x + 48, 4 + LABEL_STRIP + 40),
            Some(WHITE),
            "tile {tile} empty"
        );
        // The label's dark ink sits in the strip above the tile, and only there.
        let inked = |rows: std::ops::Range<u32>| {
            rows.flat_map(|y| (x..x + 96).map(move |x| (x, y)))
                .any(|(x, y)| image.pixel(x, y) == Some([40, 40, 40, 255]))
        };
        assert!(inked(4..4 + LABEL_STRIP), "tile {tile} has no label");
        assert!(
            !inked(4 + LABEL_STRIP..image.height()),
            "tile {tile}: ink on the picture"
        );
    }
}

#[test]
fn bad_requests_are_errors_not_panics() {
    let mut renderer = renderer();
    let scene = Scene::new(vec![unit_cube([0.5; 3])]);
    let camera = roomy_camera(View::Anterior);
    assert!(matches!(
        renderer.render(&scene, &camera, 0, 10),
        Err(RenderError::InvalidSize { .. })
    ));
    assert!(matches!(
        renderer.render(&scene, &camera, 1 << 20, 10),
        Err(RenderError::InvalidSize { .. })
    ));
    let mut broken = unit_cube([0.5; 3]);
    broken.indices[4] = 999;
    let err = renderer
        .render(&Scene::new(vec![broken]), &camera, 8, 8)
        .unwrap_err()
        .to_string();
    assert!(err.contains("vertex 999"), "{err}");
    assert!(Scene::default().bounds().is_err());
    // The renderer still works after refusing.
    assert!(renderer.render(&scene, &camera, 8, 8).is_ok());
}

#[test]
fn odd_sizes_read_back_without_row_padding_artefacts() {
    let mut renderer = renderer();
    let scene = Scene::new(vec![unit_cube([0.2, 0.6, 0.3])]);
    // 65 pixels = 260 bytes a row, padded to 512 in the readback buffer.
    let image = renderer
        .render(&scene, &roomy_camera(View::Anterior), 65, 33)
        .unwrap();
    assert_eq!(image.pixels().len(), 65 * 33 * 4);
    assert_eq!(image.pixel(64, 0), Some(WHITE));
    assert_eq!(image.pixel(64, 32), Some(WHITE));
    let ([x0, x1], [y0, y1]) = silhouette(&image, WHITE).unwrap();
    // The cube stays centred: no row is shifted by leftover padding.
    assert!(
        (x0 + x1).abs_diff(64) <= 2 && (y0 + y1).abs_diff(32) <= 2,
        "{x0}..{x1}, {y0}..{y1}"
    );
}

#[test]
fn rendered_picture_survives_png_round_trip_and_file_write() {
    let mut renderer = renderer();
    let scene = Scene::new(vec![unit_cube([0.3, 0.5, 0.7])]);
    let image = renderer
        .render(&scene, &roomy_camera(View::Oblique), SIZE, SIZE)
        .unwrap();
    let bytes = image.encode_png().unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    assert_eq!(Image::decode_png(&bytes).unwrap(), image);
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("carus-render-roundtrip.png");
    image.save_png(&path).unwrap();
    assert_eq!(
        Image::decode_png(&std::fs::read(&path).unwrap()).unwrap(),
        image
    );
}

#[test]
fn uploaded_mesh_moves_in_place_between_pictures() {
    let mut renderer = renderer();
    let camera = roomy_camera(View::Anterior);
    let cube = unit_cube([0.4, 0.6, 0.3]);
    let mut uploaded = renderer.upload(&Scene::new(vec![cube.clone()])).unwrap();
    let before = renderer
        .render_uploaded(&uploaded, &camera, SIZE, SIZE)
        .unwrap();

    // Half a unit towards the mother's right: leftwards in the anterior view.
    let mut moved = cube.clone();
    for p in &mut moved.positions {
        p[0] += 0.5;
    }
    renderer.update_mesh(&mut uploaded, 0, &moved).unwrap();
    let after = renderer
        .render_uploaded(&uploaded, &camera, SIZE, SIZE)
        .unwrap();
    let shift = camera.project(Vec3::new(0.5, 0.0, 0.0), SIZE, SIZE)[0]
        - camera.project(Vec3::ZERO, SIZE, SIZE)[0];
    let ([b0, _], _) = silhouette(&before, WHITE).unwrap();
    let ([a0, _], _) = silhouette(&after, WHITE).unwrap();
    assert!(shift < -10.0);
    assert!(
        ((a0 as f32 - b0 as f32) - shift).abs() <= 1.5,
        "moved {} px, expected {shift}",
        a0 as f32 - b0 as f32
    );

    // Another vertex count cannot be written into the same buffers.
    let mut grown = cube;
    grown.positions.push([0.0; 3]);
    grown.normals = None;
    let err = renderer
        .update_mesh(&mut uploaded, 0, &grown)
        .unwrap_err()
        .to_string();
    assert!(err.contains("upload it anew"), "{err}");
    assert!(renderer.update_mesh(&mut uploaded, 3, &moved).is_err());
}
