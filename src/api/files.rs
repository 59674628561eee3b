//! The files an entry point reads and writes: which files a robot or a scenario is made of,
//! where an identified URDF's sidecar goes, the refusal to write over an input, the versioned
//! JSON form of a result, reading logs through the data pipeline.

pub use crate::io::{
    check_outputs, check_result_dir, load_all, robot_files, scenario_files, serde_name,
    sidecar_path, versioned,
};
