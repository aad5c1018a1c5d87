//! The BVH cache end to end, through `COHORT_CACHE_DIR` as `cohort render` uses it: a large
//! scene's first run builds its tree and writes it beside the render, the next run reads
//! the same tree back, and `off` neither reads nor writes. One test in this binary, since
//! it sets the process's environment.

use cohort_render::{PreparedScene, SceneBvh};

#[test]
fn a_second_run_reads_the_tree_the_first_built() {
    let dir = std::env::temp_dir().join(format!("cohort-bvh-cache-e2e-{}", std::process::id()));
    std::env::set_var("COHORT_CACHE_DIR", &dir);
    let scene = cohort_scenes::embedded::load("stanford").expect("embedded scan");

    let first = SceneBvh::cached(&scene).unwrap();
    assert!(!first.cached, "an empty cache holds no tree");
    let file = first
        .save_to
        .clone()
        .expect("caching is on for a large scene");
    assert!(file.starts_with(&dir));
    assert!(
        !file.exists(),
        "a built tree is written only by save_beside"
    );
    let expected = (first.bvh.clone(), first.wide.clone());
    // The guard waits for the write when dropped.
    drop(PreparedScene::new(&scene, first).save_beside());
    assert!(file.exists());

    let second = SceneBvh::cached(&scene).unwrap();
    assert!(second.cached);
    assert!(
        second.save_to.is_none(),
        "a tree read back is not written again"
    );
    assert_eq!((second.bvh, second.wide), expected);

    // A damaged file is rebuilt, and the rebuilt tree is the same.
    let mut data = std::fs::read(&file).unwrap();
    let last = data.len() - 1;
    data[last] ^= 0x40;
    std::fs::write(&file, &data).unwrap();
    let rebuilt = SceneBvh::cached(&scene).unwrap();
    assert!(!rebuilt.cached);
    assert_eq!((rebuilt.bvh, rebuilt.wide), expected);

    std::env::set_var("COHORT_CACHE_DIR", "off");
    let off = SceneBvh::cached(&scene).unwrap();
    assert!(!off.cached && off.save_to.is_none());
    let _ = std::fs::remove_dir_all(&dir);
}
