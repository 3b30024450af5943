//! Prints the warnings raised when loading a URDF: `cargo run -p stride-model --example model_warnings -- <URDF>`.
fn main() {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: model_warnings <URDF>");
        std::process::exit(2);
    };
    match stride_model::Model::from_urdf_file(&path) {
        Ok(model) => {
            println!(
                "{}: {} DoF, {:.6} kg, {} frames, {} FT sensors",
                model.name(),
                model.dof(),
                model.total_mass(),
                model.frames().len(),
                model.ft_sensors().len()
            );
            for w in model.warnings() {
                println!("warning: {w}");
            }
        }
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    }
}
