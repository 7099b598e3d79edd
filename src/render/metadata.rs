//! What made a frame, as the metadata its EXR and PNG files carry
//! (`lacuna.volume`, `lacuna.tf`, `lacuna.accel`, the look, the device):
//! written alike by `render` and by `bench --frames-out`, so either file
//! says how to make it again.

use super::{FrameDesc, Scene};
use crate::error::Result;
use crate::frame::Frame;
use crate::gpu::DeviceInfo;
use crate::tf::TransferFunction;
use crate::Volume;

/// Adds the frame's metadata: the volume, the transfer function, the
/// structure with its parameters and what marched it, the frame's
/// description, the device, and the march pass's time where timed.
pub fn describe(
    frame: &mut Frame,
    (volume, tf): (&Volume, &TransferFunction),
    scene: Scene,
    desc: &FrameDesc,
    info: &DeviceInfo,
    march_ms: Option<f64>,
) -> Result<()> {
    let structure = scene.structure;
    let meta = &mut frame.metadata;
    meta.insert("volume".into(), volume.name.clone());
    meta.insert("tf".into(), tf.spec.clone());
    meta.insert("accel".into(), structure.accel().to_string());
    if let Some(m) = structure.marched_as_reason() {
        meta.insert("marched_as".into(), m.label);
    }
    for (k, v) in structure.params().describe() {
        meta.insert(k.to_string(), v);
    }
    for (k, v) in desc.describe(scene.volume) {
        meta.insert(k.to_string(), v);
    }
    meta.insert("device".into(), format!("{} ({})", info.name, info.driver));
    if let Some(ms) = march_ms {
        meta.insert("gpu_ms".into(), format!("{ms:.4}"));
    }
    Ok(())
}
