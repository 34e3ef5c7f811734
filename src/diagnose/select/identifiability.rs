//! Identifiability, before any fit: which catalogue entries this record can identify, their sensitivities at
//! the unextended model and their resolution on the record (the module doc of `select` gives the equations).

use super::super::extension::Extension;
use super::super::prepare::Prepared;
use super::super::progress::Progress;
use super::super::projection::{orthonormal_basis, project_off};
use super::super::search::{null_sensitivity, par_map, residuals, Weighted, Worker};
use super::super::{sim_err, DiagnoseError, DiagnoseOptions, Skipped};
use super::Entries;

/// Fisher information about the parameter with sensitivity `s` once the nuisance terms are estimated with it:
/// ‖(1 − P) s‖², P the projection onto the `others` columns and onto an offset on every channel whose `mask`
/// entry is set (channel-major vectors, `mask.len()` channels of equal length). The Schur complement
/// I_θθ − I_θN I_NN⁻¹ I_Nθ of the information matrix, computed by modified Gram–Schmidt.
pub fn profiled_information(s: &[f64], others: &[Vec<f64>], mask: &[bool]) -> f64 {
    let m = s.len() / mask.len().max(1);
    // An offset on a channel: remove each masked channel's mean (the offsets are orthogonal to each other).
    let demean = |v: &[f64]| -> Vec<f64> {
        let mut v = v.to_vec();
        if m == 0 {
            return v;
        }
        for (c, chunk) in v.chunks_mut(m).enumerate() {
            if mask.get(c).copied().unwrap_or(false) {
                let mean = chunk.iter().sum::<f64>() / m as f64;
                chunk.iter_mut().for_each(|x| *x -= mean);
            }
        }
        v
    };
    let demeaned: Vec<Vec<f64>> = others.iter().map(|o| demean(o)).collect();
    let basis = orthonormal_basis(&demeaned);
    let mut v = demean(s);
    project_off(&mut v, &basis);
    v.iter().map(|x| x * x).sum()
}

/// The channels (order of `case.outputs`) on which a sensor offset is a nuisance term of `e`: those whose
/// sensor bias is in the catalogue, except the one `e` itself is the bias of.
pub(super) fn offset_mask(
    outputs: &[String],
    entries: &[&dyn Extension],
    e: &dyn Extension,
) -> Vec<bool> {
    outputs
        .iter()
        .map(|c| {
            let biasable = entries
                .iter()
                .any(|x| x.effect() == "sensor_bias" && x.target() == c);
            biasable && !(e.effect() == "sensor_bias" && e.target() == c)
        })
        .collect()
}

/// What the identifiability stage hands the selection: the entries the record can identify, their
/// sensitivities at the unextended model, their resolution on this record and their nuisance masks; and the
/// entries it cannot identify, with the reason, their resolution and masks (in the order of `skipped`).
pub(super) struct Identifiable<'e> {
    pub(super) entries: Vec<&'e dyn Extension>,
    pub(super) sensitivities: Vec<Vec<f64>>,
    pub(super) resolution: Vec<f64>,
    pub(super) masks: Vec<Vec<bool>>,
    pub(super) skipped: Vec<Skipped>,
    pub(super) undetermined: Entries<'e>,
}

/// The catalogue entries the record can identify: Cramér–Rao bound 1/√I, from the information after the
/// nuisance terms ([`profiled_information`]), at most a third of the entry's resolution on this record.
pub(super) fn identifiable<'e>(
    workers: &mut [Worker],
    w: &Weighted,
    p: &'e Prepared,
    opts: &DiagnoseOptions,
    progress: &Progress,
) -> Result<Identifiable<'e>, DiagnoseError> {
    let entries = p.entries();
    let r0 = residuals(&mut workers[0], w, &[]).map_err(sim_err("replay"))?;
    progress.stage("identifiability", entries.len());
    let sens = par_map(workers, &entries, |wk, e| {
        let out = null_sensitivity(wk, w, &[], *e, &r0);
        progress.fitted();
        out
    });
    let sens: Vec<Vec<f64>> = sens
        .into_iter()
        .collect::<Result<_, _>>()
        .map_err(sim_err("replay"))?;
    let masks: Vec<Vec<bool>> = entries
        .iter()
        .map(|e| offset_mask(&w.case.outputs, &entries, *e))
        .collect();
    let info: Vec<f64> = sens
        .iter()
        .zip(&masks)
        .map(|(s, mask)| profiled_information(s, &[], mask))
        .collect();
    let resolution: Vec<f64> = entries
        .iter()
        .zip(&info)
        .map(|(e, &i_k)| {
            let own = e.params()[0].resolution;
            let Some((effect, target)) = e.refines() else {
                return own;
            };
            match entries
                .iter()
                .position(|x| x.effect() == effect && x.target() == target)
            {
                Some(j) if i_k > 0.0 => {
                    let lin = entries[j].params()[0].resolution;
                    own.max(opts.refinement_share * lin * (info[j] / i_k).sqrt())
                }
                Some(_) => f64::INFINITY,
                None => own,
            }
        })
        .collect();
    let mut out = Identifiable {
        entries: Vec::new(),
        sensitivities: Vec::new(),
        resolution: Vec::new(),
        masks: Vec::new(),
        skipped: Vec::new(),
        undetermined: Entries::default(),
    };
    for ((((e, s), i), res), mask) in entries
        .into_iter()
        .zip(sens)
        .zip(info)
        .zip(resolution)
        .zip(masks)
    {
        let crb = 1.0 / i.sqrt();
        let determined = 3.0 * crb <= res; // false for a NaN bound too
        if !determined {
            out.skipped.push(Skipped {
                effect: e.effect().into(),
                target: e.target().into(),
                reason: format!(
                    "the record cannot identify it: Cramér–Rao σ {crb:.3e} from the Fisher information after \
                     the nuisance terms exceeds a third of the resolution {res:.3} on this record"
                ),
            });
            out.undetermined.catalogue.push(e);
            out.undetermined.resolution.push(res);
            out.undetermined.masks.push(mask);
        } else {
            out.entries.push(e);
            out.sensitivities.push(s);
            out.resolution.push(res);
            out.masks.push(mask);
        }
    }
    Ok(out)
}
