//! `lacuna export`: any volume lacuna loads or generates as an Open
//! SciVis-named raw file in its source units, for VTK, ParaView and others.

use super::{parse_dims, parse_type};
use clap::Args;
use lacuna::error::number;
use lacuna::volume::{check_raw_out, parse_export_type, write_raw, LoadOptions, RawLayout, Series, VoxelType};
use lacuna::Result;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args)]
pub struct ExportArgs {
    /// A file (.raw, .nrrd, .nhdr, .nii, .nii.gz) or NAME:SIZE[:PARAM] (menger, nbody, vessels, turbulence, shells).
    volume: String,
    /// Output: a stem (_WxHxD_TYPE.raw is appended) or the Open SciVis name NAME_WxHxD_TYPE.raw.
    out: PathBuf,
    /// Voxel type written: uint8, uint16 or float32 (default: the source type if it is one of them
    /// and holds every value, else the smallest that does).
    #[arg(long = "type", value_name = "TYPE", value_parser = parse_export_type)]
    ty: Option<VoxelType>,
    /// Dimensions of a raw input file whose name does not give them (WxHxD).
    #[arg(long, requires = "source_type", value_parser = parse_dims)]
    dims: Option<[u32; 3]>,
    /// Voxel type of a raw input file whose name does not give it (render's --type).
    #[arg(long, value_name = "TYPE", requires = "dims", value_parser = parse_type)]
    source_type: Option<VoxelType>,
    /// Time step of a series (a file pattern, a NIfTI time axis, or a generator's animation), from 0.
    #[arg(long, default_value_t = 0)]
    time: u32,
}

pub fn run(args: &ExportArgs) -> Result<ExitCode> {
    // The output's folder is checked before a (possibly long) load.
    check_raw_out(&args.out)?;
    // Every volume opens as a series (one step where it has no time axis),
    // so a file pattern's step 0 is read as its other steps are.
    let raw = args.dims.zip(args.source_type).map(|(dims, ty)| RawLayout { dims, ty });
    // Values are written in source units: no normalisation applies.
    let series = Series::open(&args.volume, &LoadOptions { raw, value_range: None })?;
    series.check_step(args.time)?;
    let volume = series.load(args.time, None)?;
    let written = write_raw(&volume, &args.out, args.ty)?;
    say!("{}", written.path.display());
    if written.within > 0.0 {
        let [lo, hi] = volume.value_range;
        say_err!(
            "note: {} voxels are kept normalised to 0 .. 1 in float32 over their range ({} .. {}), so each exported value is within {:.3e} of the file's, not a bit-exact copy",
            volume.source_type,
            number(lo),
            number(hi),
            written.within
        );
    }
    let [sx, sy, sz] = volume.spacing;
    if volume.spacing != [1.0; 3] {
        say_err!(
            "note: the spacing {sx} x {sy} x {sz} is not stored in a raw file; lacuna's raw loader has no spacing \
             option and reads 1 x 1 x 1 (in ParaView set the reader's Data Spacing to {sx} {sy} {sz})"
        );
    }
    Ok(ExitCode::SUCCESS)
}
