//! The iCub-models rule on each value of `STRIDE_ICUB_MODELS_DIR`: unset, not a folder, an empty folder, a
//! folder without the requested model, and the real layout (built in a temporary folder).

use std::ffi::OsStr;
use std::path::PathBuf;

use stride_testkit::{resolve_icub_model_urdf, resolve_icub_models_dir, IcubModelsError};

/// A fresh, empty temporary folder unique to this process and `name`.
fn empty_folder(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("stride-testkit-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temporary folder");
    dir
}

#[test]
fn unset_means_skip() {
    assert_eq!(resolve_icub_models_dir(None), Ok(None));
    assert_eq!(resolve_icub_model_urdf(None, "iCubGenova04"), Ok(None));
}

#[test]
fn set_but_not_a_folder_fails() {
    let dir = empty_folder("not-a-folder");
    let file = dir.join("file");
    std::fs::write(&file, "").unwrap();
    for var in [file.clone(), dir.join("missing")] {
        assert_eq!(
            resolve_icub_models_dir(Some(var.as_os_str())),
            Err(IcubModelsError::NotAFolder(var.clone()))
        );
    }
    assert_eq!(
        resolve_icub_models_dir(Some(OsStr::new(""))),
        Err(IcubModelsError::NotAFolder(PathBuf::new()))
    );
}

#[test]
fn set_to_an_empty_folder_fails() {
    let dir = empty_folder("empty");
    let expected = IcubModelsError::MissingUrdf(dir.join("iCubGazeboV2_7").join("model.urdf"));
    assert_eq!(
        resolve_icub_models_dir(Some(dir.as_os_str())),
        Err(expected.clone())
    );
    assert_eq!(
        resolve_icub_model_urdf(Some(dir.as_os_str()), "iCubGenova04"),
        Err(expected)
    );
}

#[test]
fn the_models_folder_gives_each_present_model_and_fails_on_others() {
    let dir = empty_folder("models");
    for model in ["iCubGazeboV2_7", "iCubGenova04"] {
        std::fs::create_dir_all(dir.join(model)).unwrap();
        std::fs::write(dir.join(model).join("model.urdf"), "<robot/>").unwrap();
    }
    assert_eq!(
        resolve_icub_models_dir(Some(dir.as_os_str())),
        Ok(Some(dir.clone()))
    );
    let urdf = dir.join("iCubGenova04").join("model.urdf");
    assert_eq!(
        resolve_icub_model_urdf(Some(dir.as_os_str()), "iCubGenova04"),
        Ok(Some(urdf))
    );
    assert_eq!(
        resolve_icub_model_urdf(Some(dir.as_os_str()), "iCubLisboa01"),
        Err(IcubModelsError::MissingUrdf(
            dir.join("iCubLisboa01").join("model.urdf")
        ))
    );
}

#[test]
#[should_panic(expected = "is one word")]
fn a_test_name_with_spaces_is_refused() {
    let _ = stride_testkit::icub_models_dir("two words");
}
