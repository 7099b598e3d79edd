//! Sorts N random u32 keys with u32 payloads on the GPU (default 2^24),
//! checks the result against the CPU's stable sort, and prints keys per
//! second from GPU timestamps (median of 5 sorts after one warm-up).
//!
//!     cargo run --release --example radix_sort -- [N] [KEY_BITS]

use lacuna::gpu::{vk, Buffer, Context, ContextOptions, Timer};
use lacuna::prims::RadixSort;

fn main() -> lacuna::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let n: u64 = args
        .get(1)
        .map_or(Ok(1 << 24), |s| s.parse())
        .map_err(|_| lacuna::Error::invalid("N", &args[1], "not a count"))?;
    let bits: u32 = args
        .get(2)
        .map_or(Ok(32), |s| s.parse())
        .map_err(|_| lacuna::Error::invalid("KEY_BITS", &args[2], "not a number"))?;
    let ctx = Context::new(&ContextOptions::from_env())?;
    let sort = RadixSort::new(&ctx)?;
    let scratch = sort.scratch(n)?;
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let keys: Vec<u32> = (0..n)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state as u32
        })
        .collect();
    let vals: Vec<u32> = (0..n as u32).collect();
    let usage =
        vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST;
    let (kb, vb) = (
        Buffer::with_data(&ctx, "keys", bytemuck::cast_slice(&keys), usage)?,
        Buffer::with_data(&ctx, "values", bytemuck::cast_slice(&vals), usage)?,
    );
    let mut timer = Timer::new(&ctx, 1)?;
    let mut ms = Vec::new();
    for run in 0..6 {
        if run > 0 {
            kb.upload(0, bytemuck::cast_slice(&keys))?;
            vb.upload(0, bytemuck::cast_slice(&vals))?;
        }
        ctx.submit_and_wait(|cmd| {
            timer.reset(cmd);
            let pass = timer.begin(cmd, "sort")?;
            sort.record(cmd, &kb, &vb, n, bits, &scratch)?;
            timer.end(cmd, pass);
            Ok(())
        })?;
        if run > 0 {
            ms.push(timer.results()?.get("sort").unwrap_or(f64::NAN));
        }
    }
    let got_k: Vec<u32> = bytemuck::pod_collect_to_vec(&kb.download(0, n * 4)?);
    let got_v: Vec<u32> = bytemuck::pod_collect_to_vec(&vb.download(0, n * 4)?);
    let mask = if bits == 32 { u32::MAX } else { (1u32 << bits) - 1 };
    let mut want: Vec<(u32, u32)> = keys.iter().cloned().zip(vals).collect();
    want.sort_by_key(|(k, _)| k & mask);
    let ok = want
        .iter()
        .zip(got_k.iter().zip(&got_v))
        .all(|((wk, wv), (k, v))| wk == k && wv == v);
    ms.sort_by(f64::total_cmp);
    let median = ms[ms.len() / 2];
    println!("device {}", ctx.info().name);
    println!(
        "sorted {n} keys ({bits} bits) with payloads: {}",
        if ok {
            "matches the CPU's stable sort"
        } else {
            "MISMATCH"
        }
    );
    println!(
        "median {median:.2} ms over {} sorts: {:.1} Mkeys/s",
        ms.len(),
        n as f64 / median / 1e3
    );
    if !ok {
        std::process::exit(1);
    }
    Ok(())
}
