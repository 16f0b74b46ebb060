//! Why a scene could not be loaded, as one line naming the file and the line, field or
//! JSON path at fault.

/// A path as error messages show it: on one line whatever characters it holds.
pub fn shown(path: &std::path::Path) -> String {
    path.display().to_string().escape_debug().to_string()
}

/// Why a scene could not be loaded. Each message is one line naming the file and the
/// line or field at fault.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}:{line}:{column}: {message}")]
    Syntax {
        path: String,
        line: usize,
        column: usize,
        message: String,
    },
    #[error("{path}: {field}: {message}")]
    Invalid {
        path: String,
        field: String,
        message: String,
    },
    /// An image that cannot be read as a texture.
    #[error("{path}: {message}")]
    Image { path: String, message: String },
    /// A problem with a glTF file at `at`: a JSON path such as
    /// `meshes[2].primitives[0].indices`, or a part of a `.glb` container.
    #[error("{path}: {at}: {message}")]
    Gltf {
        path: String,
        at: String,
        message: String,
    },
    /// A file that is none of the inputs meshtrace reads.
    #[error("{path}: {message}")]
    Unsupported { path: String, message: String },
    /// A problem with an OBJ file or an MTL library it loads (`path` names the file at
    /// fault), at `line` when one line is at fault; whole-mesh problems have no line.
    #[error("{path}{}: {message}", at_line(*.line))]
    Obj {
        path: String,
        line: Option<usize>,
        message: String,
    },
}

/// The `:{line}` of an error message, or nothing when the line is not known.
fn at_line(line: Option<usize>) -> String {
    line.map(|l| format!(":{l}")).unwrap_or_default()
}
