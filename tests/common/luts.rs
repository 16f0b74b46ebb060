//! Blender's colour-management LUTs, which the Filmic and AgX view transforms read.

use meshtrace::film::{DisplayTransform, ViewTransform, lut_folder};

/// The view loaded, or `None` after saying why the test skips (its LUTs are not here,
/// MESHTRACE_BLENDER_LUTS naming none); CI sets MESHTRACE_REQUIRE_BLENDER_LUTS=1, which
/// makes their absence a failure instead.
pub fn view_or_skip(test: &str, view: ViewTransform) -> Option<DisplayTransform> {
    if let Err(e) = lut_folder(view) {
        let required = std::env::var("MESHTRACE_REQUIRE_BLENDER_LUTS").is_ok_and(|v| v == "1");
        assert!(!required, "MESHTRACE_REQUIRE_BLENDER_LUTS=1 but {e}");
        eprintln!("{test}: skipped: {e}");
        return None;
    }
    Some(DisplayTransform::load(view).unwrap_or_else(|e| panic!("{e}")))
}
