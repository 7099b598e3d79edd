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

/// What a frame was made of: the volume, step `time` of a series (None:
/// one volume), and its transfer function.
pub struct Source<'a> {
    pub volume: &'a Volume,
    pub time: Option<u32>,
    pub tf: &'a TransferFunction,
}

/// Adds the frame's metadata: the volume and its step, the transfer
/// function, the structure with its parameters and what marched it, the
/// frame's description, the device, and the march pass's time where timed.
pub fn describe(
    frame: &mut Frame,
    Source { volume, time, tf }: Source,
    scene: Scene,
    desc: &FrameDesc,
    info: &DeviceInfo,
    march_ms: Option<f64>,
) -> Result<()> {
    let structure = scene.structure;
    let meta = &mut frame.metadata;
    meta.insert("volume".into(), volume.name.clone());
    if let Some(k) = time {
        meta.insert("time".into(), k.to_string());
    }
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
