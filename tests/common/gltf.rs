//! glTF files built in tests: a JSON document (serde_json) and one binary buffer, written as
//! a `.gltf` with the buffer embedded (a base64 data URI) or beside it (a `.bin`), or as a
//! `.glb`.

use serde_json::{Value, json};

/// glTF component types.
pub const BYTE: u32 = 5120;
pub const UNSIGNED_BYTE: u32 = 5121;
pub const SHORT: u32 = 5122;
pub const UNSIGNED_SHORT: u32 = 5123;
pub const UNSIGNED_INT: u32 = 5125;
pub const FLOAT: u32 = 5126;

/// A glTF document under construction, with its binary buffer (buffer 0).
#[derive(Clone)]
pub struct Asset {
    pub json: Value,
    pub bin: Vec<u8>,
}

impl Default for Asset {
    fn default() -> Self {
        Self::new()
    }
}

impl Asset {
    /// An empty glTF 2.0 document.
    pub fn new() -> Self {
        Self {
            json: json!({ "asset": { "version": "2.0" } }),
            bin: Vec::new(),
        }
    }

    /// Appends `value` to the top-level array `key` (made if absent); returns its index.
    pub fn push(&mut self, key: &str, value: Value) -> usize {
        let array = self.json[key].as_array_mut();
        match array {
            Some(a) => {
                a.push(value);
                a.len() - 1
            }
            None => {
                self.json[key] = json!([value]);
                0
            }
        }
    }

    /// Appends bytes to the buffer (at a 4-byte boundary) as a new buffer view; returns
    /// the view's index.
    pub fn view(&mut self, bytes: &[u8], stride: Option<usize>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        let mut view = json!({ "buffer": 0, "byteOffset": offset, "byteLength": bytes.len() });
        if let Some(s) = stride {
            view["byteStride"] = json!(s);
        }
        self.push("bufferViews", view)
    }

    /// An accessor of `count` elements of `ty` over a new view of `bytes`.
    pub fn accessor(
        &mut self,
        bytes: &[u8],
        component_type: u32,
        count: usize,
        ty: &str,
        normalized: bool,
    ) -> usize {
        let view = self.view(bytes, None);
        let mut a = json!({
            "bufferView": view, "componentType": component_type, "count": count, "type": ty,
        });
        if normalized {
            a["normalized"] = json!(true);
        }
        self.push("accessors", a)
    }

    /// A float accessor of `ty` (`components` floats an element).
    pub fn floats(&mut self, values: &[f32], ty: &str) -> usize {
        let components = match ty {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            "VEC4" => 4,
            other => panic!("no float accessors of {other} here"),
        };
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.accessor(&bytes, FLOAT, values.len() / components, ty, false)
    }

    /// A VEC3 float accessor of positions.
    pub fn positions(&mut self, points: &[[f32; 3]]) -> usize {
        let flat: Vec<f32> = points.iter().flatten().copied().collect();
        self.floats(&flat, "VEC3")
    }

    /// An unsigned int index accessor.
    pub fn indices(&mut self, indices: &[u32]) -> usize {
        let bytes: Vec<u8> = indices.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.accessor(&bytes, UNSIGNED_INT, indices.len(), "SCALAR", false)
    }

    /// A mesh of one primitive; returns the mesh's index.
    pub fn mesh(&mut self, primitive: Value) -> usize {
        self.push("meshes", json!({ "primitives": [primitive] }))
    }

    /// A node; returns its index.
    pub fn node(&mut self, node: Value) -> usize {
        self.push("nodes", node)
    }

    /// Scene 0, the default, with these root nodes.
    pub fn scene(&mut self, nodes: &[usize]) {
        self.json["scenes"] = json!([{ "nodes": nodes }]);
        self.json["scene"] = json!(0);
    }

    /// One triangle mesh in one node, the scene's only root: positions (0,0,0), (1,0,0),
    /// (0,1,0), with `extra` attributes and properties merged into the primitive.
    pub fn triangle(&mut self, extra: Value) -> usize {
        let p = self.positions(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        let mut primitive = json!({ "attributes": { "POSITION": p } });
        merge(&mut primitive, extra);
        let mesh = self.mesh(primitive);
        let node = self.node(json!({ "mesh": mesh }));
        self.scene(&[node]);
        mesh
    }

    /// The buffer's entry: `uri` (none for a GLB's BIN chunk) and its length.
    fn with_buffer(&self, uri: Option<String>) -> Value {
        let mut json = self.json.clone();
        if !self.bin.is_empty() {
            let mut buffer = json!({ "byteLength": self.bin.len() });
            if let Some(uri) = uri {
                buffer["uri"] = json!(uri);
            }
            json["buffers"] = json!([buffer]);
        }
        json
    }

    /// A `.gltf` with its buffer embedded as a base64 data URI.
    pub fn embedded(&self) -> Vec<u8> {
        let uri = format!("data:application/octet-stream;base64,{}", base64(&self.bin));
        serde_json::to_vec_pretty(&self.with_buffer(Some(uri))).expect("JSON")
    }

    /// A `.gltf` whose buffer is the file `bin` beside it: (the JSON, the buffer's bytes).
    pub fn external(&self, bin: &str) -> (Vec<u8>, Vec<u8>) {
        let json = serde_json::to_vec_pretty(&self.with_buffer(Some(bin.to_string())));
        (json.expect("JSON"), self.bin.clone())
    }

    /// A `.glb`: the JSON chunk and the buffer as its BIN chunk.
    pub fn glb(&self) -> Vec<u8> {
        let json = serde_json::to_vec(&self.with_buffer(None)).expect("JSON");
        glb(&json, (!self.bin.is_empty()).then_some(&self.bin[..]))
    }
}

/// A GLB container of a JSON chunk and an optional BIN chunk, each padded to 4 bytes.
pub fn glb(json: &[u8], bin: Option<&[u8]>) -> Vec<u8> {
    let pad = |data: &[u8], with: u8| {
        let mut d = data.to_vec();
        while !d.len().is_multiple_of(4) {
            d.push(with);
        }
        d
    };
    let mut chunks = Vec::new();
    let json = pad(json, b' ');
    chunks.extend((json.len() as u32).to_le_bytes());
    chunks.extend(b"JSON");
    chunks.extend(&json);
    if let Some(bin) = bin {
        let bin = pad(bin, 0);
        chunks.extend((bin.len() as u32).to_le_bytes());
        chunks.extend(b"BIN\0");
        chunks.extend(&bin);
    }
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend(((12 + chunks.len()) as u32).to_le_bytes());
    out.extend(chunks);
    out
}

/// Merges the object `extra` into the object `into`, key by key (objects recursively).
pub fn merge(into: &mut Value, extra: Value) {
    match (into, extra) {
        (Value::Object(a), Value::Object(b)) => {
            for (k, v) in b {
                merge(a.entry(k).or_insert(Value::Null), v);
            }
        }
        (slot, v) => *slot = v,
    }
}

/// Standard base64 with padding.
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = u32::from(b[0]) << 16 | u32::from(b[1]) << 8 | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// An 8-bit RGBA PNG of `width` × `height` texels, row by row from the top, in memory.
pub fn png(width: u32, height: u32, texels: &[[u8; 4]]) -> Vec<u8> {
    let data: Vec<u8> = texels.iter().flatten().copied().collect();
    let image = image::RgbaImage::from_raw(width, height, data).expect("width × height texels");
    let mut out = std::io::Cursor::new(Vec::new());
    image
        .write_to(&mut out, image::ImageFormat::Png)
        .expect("PNG encoding");
    out.into_inner()
}
