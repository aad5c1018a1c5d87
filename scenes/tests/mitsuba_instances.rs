//! `shapegroup` and `instance` read as Mitsuba 3 reads them: a group is drawn only where an
//! instance places it, each instance adds the group's shapes under its `to_world`, and what
//! Mitsuba refuses (emitters in a group, nested instancing, an instance without a group) is
//! a located error.

use cohort_scenes::{load_mitsuba_str, Loaded};
use glam::Vec3;

fn load(body: &str) -> Result<Loaded, String> {
    let xml = format!(r#"<scene version="3.0.0">{body}</scene>"#);
    load_mitsuba_str(&xml, ".").map_err(|e| e.to_string())
}

const GROUP: &str = r#"<shape type="shapegroup" id="g">
    <shape type="rectangle"/>
    <shape type="cube"><transform name="to_world"><scale value="0.5"/><translate z="2"/></transform></shape>
</shape>"#;

fn bounds(l: &Loaded) -> (Vec3, Vec3) {
    let p = &l.scene.triangles.positions;
    let lo = p.iter().fold(Vec3::splat(f32::MAX), |a, &b| a.min(b));
    let hi = p.iter().fold(Vec3::splat(f32::MIN), |a, &b| a.max(b));
    (lo, hi)
}

#[test]
fn a_group_alone_draws_nothing() {
    let l = load(GROUP).unwrap();
    assert_eq!(l.scene.triangles.len(), 0);
}

#[test]
fn each_instance_places_the_whole_group() {
    let l = load(&format!(
        r#"{GROUP}
<shape type="instance"><ref id="g"/><transform name="to_world"><translate x="10"/></transform></shape>
<shape type="instance"><ref id="g"/><transform name="to_world"><scale value="2"/><translate y="-10"/></transform></shape>"#
    ))
    .unwrap();
    // A rectangle (2 triangles) and a cube (12), twice.
    assert_eq!(l.scene.triangles.len(), 2 * 14);
    let (lo, hi) = bounds(&l);
    // First instance: x in [9, 11]; second: scaled by 2 then moved down, y in [-12, -8].
    assert!(
        (hi.x - 11.0).abs() < 1e-5 && (lo.y + 12.0).abs() < 1e-5,
        "{lo} {hi}"
    );
    // The cube's own to_world applies inside the instance's: z up to (2 + 0.5) * 2.
    assert!((hi.z - 5.0).abs() < 1e-5, "{hi}");
    assert_eq!(l.scene.objects.len(), 4);
}

#[test]
fn what_mitsuba_refuses_is_a_located_error() {
    for (body, expect, line) in [
        (
            r#"<shape type="shapegroup" id="g">
<shape type="rectangle"><emitter type="area"/></shape></shape>
<shape type="instance"><ref id="g"/></shape>"#,
            "instancing emitters",
            ":2:",
        ),
        (
            r#"<shape type="shapegroup" id="g">
<shape type="shapegroup"/></shape>"#,
            "nested instancing",
            ":2:",
        ),
        (
            r#"
<shape type="instance"/>"#,
            "needs a shapegroup",
            ":2:",
        ),
    ] {
        let e = load(body).unwrap_err();
        assert!(e.contains(expect) && e.contains(line), "{body}: {e}");
    }
}
