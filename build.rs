//! With the `mujoco` feature, bakes MuJoCo's library folder (`MUJOCO_DYNAMIC_LINK_DIR`, printed by
//! `tools/mujoco/setup.sh`) into the rpath of the `stride` binary and the end-to-end tests, so they load
//! `libmujoco.so.3.17.0` without `LD_LIBRARY_PATH` (a dependency's build script cannot set link arguments
//! of this package's binaries). Without the feature it does nothing.

fn main() {
    println!("cargo::rerun-if-env-changed=MUJOCO_DYNAMIC_LINK_DIR");
    if std::env::var_os("CARGO_FEATURE_MUJOCO").is_none() {
        return;
    }
    if let Some(dir) = std::env::var_os("MUJOCO_DYNAMIC_LINK_DIR") {
        println!("cargo::rustc-link-arg=-Wl,-rpath,{}", dir.to_string_lossy());
    }
}
