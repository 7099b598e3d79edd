//! Another time step on a `GpuVolume`: its voxels, and what `prepare`
//! added for the last step, written where the last step's were.

use super::delta::StepDelta;
use super::filter::Filter;
use super::gpu::{resolve_storage, texels, StepMark};
use super::pool::Storage;
use super::{cells, cells_delta, gradient_cells};
use super::{channels, GpuVolume, Volume};
use crate::error::Result;
use crate::gpu::{Context, TexelBuffer};
use std::sync::Arc;

/// The edge of the bricks a step's changed texels are uploaded in.
const UPLOAD_BRICK: u32 = 16;

impl GpuVolume {
    /// Puts `volume`, another step on this volume's grid (the same dims,
    /// channels and texel kind, dense storage), in place of the voxels this
    /// holds, with the cells copy, gradient and gradient cells copy it has
    /// made for `volume`, and waits. The image keeps its memory (the voxels
    /// pass through staging as in an upload), and on a CPU device the host
    /// packs the copies into the memory the last step's filled: no new
    /// memory to fault in, which was two thirds of nbody:256's upload on
    /// lavapipe. On other devices the cells copies are made anew. Returns
    /// false, changing nothing, where `volume` does not fit (other dims,
    /// channels or texel kind, or bricked storage); upload it anew then.
    ///
    /// `previous`, where the caller still has it, is the step these
    /// texels came from (`upload` or the last `replace` had it): then only
    /// what changed is rewritten (`StepDelta`), the cells copy around the
    /// changed voxels on a CPU device, the image's changed bricks
    /// (`upload_changed`) or else its changed texels in the staging buffer
    /// this keeps with the last step's (where the image fits one), and the
    /// step is marked with what changed (`step_mark`), so the next build
    /// recomputes only the value ranges of the bricks whose apron holds a
    /// changed voxel. Passing a volume these
    /// texels did not come from leaves stale texels: the delta is trusted.
    /// On a CPU device, where this keeps that staging buffer from the last
    /// `replace` (the image copied whole, where it fits one), the delta is
    /// found by comparing it with `volume` as it is brought up to date, and
    /// `previous` is not read.
    ///
    /// No submission reading this volume may still be pending (the host
    /// writes memory the device reads). After an error its contents are
    /// unspecified: drop it.
    pub fn replace(&mut self, volume: &Volume, previous: Option<&Volume>) -> Result<bool> {
        volume.check()?;
        if let Some(p) = previous {
            p.check()?;
        }
        let fits = self.pool.is_none()
            && volume.dims == self.dims
            && volume.channel_count() as u32 == self.channels
            && channels::common_kind(volume) == self.kind;
        if !fits {
            return Ok(false);
        }
        let (_, _, bytes) = texels(volume)?;
        let last = self.step.as_ref().map(|m| m.id);
        // A step of its own until it is in place: after an error no build
        // takes the last step's ranges for these texels.
        self.step = Some(StepMark::new(None));
        let shared = cells::host_shared(&self.ctx);
        let mirrored = !self.upload_changed && self.image.mirrorable();
        // On a CPU device (staging memory is the host's own; elsewhere it
        // may be write-combined, slow to read) the mirror of the last
        // step's texels, where kept, is compared with the step as it is
        // brought up to date (`StepDelta::of_texels_updating`): the step
        // before is not needed.
        let from_mirror = mirrored
            && shared
            && self
                .image_mirror
                .as_ref()
                .is_some_and(|m| m.size() >= bytes.len() as u64);
        let mut delta = match from_mirror {
            true => None,
            false => previous.and_then(|p| StepDelta::between(p, volume)).map(Arc::new),
        };
        // On a CPU device the host packs the cells copy, while the device
        // copies the image where it can (`upload_mirrored`).
        let host_cells =
            |cells: &mut Option<TexelBuffer>, delta: Option<&StepDelta>| match cells.as_mut().filter(|_| shared) {
                Some(copy) => match delta {
                    Some(delta) => cells_delta::repack_changed(copy, volume, delta),
                    None => cells::repack_shared(copy, volume),
                },
                None => Ok(()),
            };
        match delta.as_ref().filter(|_| self.upload_changed) {
            // Only the bricks that changed (nbody:256: two fifths of them).
            Some(delta) => {
                self.image_mirror = None;
                self.image
                    .upload_boxes_through(&bytes, &delta.boxes(UPLOAD_BRICK), &mut self.step_staging)?;
                host_cells(&mut self.cells, Some(delta))?;
            }
            // The changed texels into the mirror of the last step's, where
            // the whole image is copied (a GPU without the step before at
            // hand gains nothing by keeping one).
            None if mirrored => {
                let found = std::cell::OnceCell::new();
                // Called where the mirror was kept (else it is filled anew).
                let update = |mirror: &mut [u8]| match &delta {
                    Some(known) if known.copy_changed(&bytes, mirror) => {}
                    Some(_) => mirror.copy_from_slice(&bytes),
                    None => match StepDelta::of_texels_updating(self.dims, mirror, &bytes) {
                        Some(d) => drop(found.set(Arc::new(d))),
                        None => mirror.copy_from_slice(&bytes),
                    },
                };
                let cells = &mut self.cells;
                let meanwhile = || host_cells(cells, found.get().or(delta.as_ref()).map(|d| &**d));
                self.image
                    .upload_mirrored(&bytes, &mut self.image_mirror, Some(update), meanwhile)?;
                delta = found.into_inner().or(delta);
            }
            None => {
                self.image_mirror = None;
                self.image.upload_through(&bytes, &mut self.step_staging)?;
                host_cells(&mut self.cells, delta.as_deref())?;
            }
        }
        self.step = Some(StepMark::new(last.zip(delta)));
        self.spacing = volume.spacing;
        self.norm = volume.norm;
        self.norms = std::array::from_fn(|c| volume.channels().nth(c).map_or([0.0; 2], |v| v.norm));
        self.has_nan = volume.no_data_total() > 0;
        if self.cells.is_some() && !shared {
            // Made again from the image by the device's kernel.
            self.cells = None;
            self.cells_kernel = None;
            self.add_cells(volume)?;
        }
        if self.gradient.is_some() {
            let gradient = self.gradient_texels(volume)?;
            if let Some(image) = &self.gradient {
                image.upload_through(bytemuck::cast_slice(&gradient), &mut self.step_staging)?;
            }
            if let Some(copy) = &mut self.gradient_cells {
                if shared {
                    gradient_cells::repack_gradient_shared(copy, &gradient, self.dims)?;
                } else {
                    // The last step's copy (48 bytes a voxel) freed before
                    // the new one is made, so the two never coexist.
                    self.gradient_cells = None;
                    self.gradient_cells = Some(gradient_cells::upload_gradient_cells(&self.ctx, &gradient, self.dims)?);
                }
            }
        }
        Ok(true)
    }

    /// `volume` uploaded with `storage` and prepared (`prepare`), in the
    /// memory of `last` (the series' step before, with that step's voxels
    /// where the caller still has them: `replace`) where it fits, else
    /// anew, `last` dropped first. Dense steps are marked (`step_mark`).
    pub fn upload_step(
        ctx: &Context,
        last: Option<(GpuVolume, Option<&Volume>)>,
        volume: &Volume,
        storage: Storage,
        lit: bool,
        filter: Option<Filter>,
    ) -> Result<GpuVolume> {
        let dense = resolve_storage(ctx, volume, storage) == Storage::Dense;
        if let (true, Some((mut gv, previous))) = (dense, last) {
            if gv.replace(volume, previous)? {
                gv.prepare(volume, lit, filter)?;
                return Ok(gv);
            }
        }
        let mut gv = GpuVolume::upload_as(ctx, volume, storage)?;
        gv.prepare(volume, lit, filter)?;
        if dense {
            gv.step = Some(StepMark::new(None));
        }
        Ok(gv)
    }

    /// The context it was uploaded with.
    pub fn context(&self) -> &Context {
        &self.ctx
    }

    /// Which series step this is and what changed since the step before
    /// (None: not a dense step of `upload_step`).
    pub fn step_mark(&self) -> Option<&StepMark> {
        self.step.as_ref()
    }

    /// Which texels it holds: unique to this upload, and to each step
    /// `replace` put in its memory since. A structure or ranges built from
    /// it are for these texels only (`Structure::check_built_for`).
    pub fn content_id(&self) -> u64 {
        self.step.as_ref().map_or(self.uploaded, |m| m.id)
    }
}
