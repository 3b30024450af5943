//! With the `mujoco` feature, bakes MuJoCo's library folder (`MUJOCO_DYNAMIC_LINK_DIR`, the folder
//! `tools/mujoco/setup.sh` prints) into the rpath of this crate's tests and examples, so they find
//! `libmujoco.so.3.17.0` without `LD_LIBRARY_PATH` (its SONAME is versioned). Link arguments of a build
//! script only reach the package's own targets: the `stride` binary gets the same rpath from the root
//! package's build script.

fn main() {
    println!("cargo::rerun-if-env-changed=MUJOCO_DYNAMIC_LINK_DIR");
    if std::env::var_os("CARGO_FEATURE_MUJOCO").is_none() {
        return;
    }
    if let Some(dir) = std::env::var_os("MUJOCO_DYNAMIC_LINK_DIR") {
        println!("cargo::rustc-link-arg=-Wl,-rpath,{}", dir.to_string_lossy());
    }
}
