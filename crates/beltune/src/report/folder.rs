//! A result folder as a whole: [`ResultFolder::read`] is the one reader
//! (`compare`, the tuning page), [`ResultSet`] the one writer (`commission`
//! on a simulated axis, on EtherCAT and from a recording; the tuning page's
//! saved sets). A set holds `commissioning.json`, `controller.toml`,
//! `report.html` and the data files, made from the same numbers and written
//! together ([`crate::record::folder::OutputTarget::write`]).

use super::build::{
    bootstrap_overlay, build_report, excitation_plot, move_plots, ReportInputs, ReportKind,
};
use super::data_files::DataFiles;
use super::plot_data::{frf_lines, loop_data};
use super::Report;
use crate::commission::recorded::RecordedCommissioning;
use crate::commission::stiffness::TargetStiffness;
use crate::commission::validation::MoveResult;
use crate::commission::Commissioning;
use crate::design::ControllerDesign;
use crate::ident::FitModel;
use crate::model::rigs::Plant;
use crate::record::commissioning::{CommissioningRecord, Origin, Tuning};
use crate::record::controller::ControllerFile;
use crate::record::folder::OutputTarget;
use crate::record::model::FrictionResult;
use crate::record::provenance::Provenance;
use crate::record::{COMMISSIONING_FILE, CONTROLLER_FILE, REPORT_FILE};
use crate::report::FrictionPlot;
use crate::verdict::Verdict;
use crate::Result;
use std::path::{Path, PathBuf};

/// A result folder as read: the record and the data files beside it.
#[derive(Clone, Debug)]
pub struct ResultFolder {
    /// The folder.
    pub dir: PathBuf,
    /// `commissioning.json`.
    pub record: CommissioningRecord,
    /// The data files (each optional); the friction runs carry the record's
    /// fitted friction.
    pub data: DataFiles,
}

impl ResultFolder {
    /// Read `dir/commissioning.json` (a regular file of at most
    /// [`crate::io::MAX_TEXT_BYTES`], checked as [`CommissioningRecord::parse`]
    /// says) and the data files beside it. Every error names the file.
    pub fn read(dir: &Path) -> Result<ResultFolder> {
        let record = CommissioningRecord::load(&dir.join(COMMISSIONING_FILE))?;
        let mut data = DataFiles::read(dir)?;
        match (&record.friction, &mut data.friction) {
            (Some(f), Some(plot)) => {
                plot.viscous_nm_s_per_rad = f.viscous_nm_s_per_rad;
                plot.coulomb_nm = f.coulomb_nm;
            }
            // runs without a fit are not shown
            (None, _) => data.friction = None,
            _ => {}
        }
        Ok(ResultFolder {
            dir: dir.to_path_buf(),
            record,
            data,
        })
    }
}

/// The files of one result, made from the same numbers.
#[derive(Clone, Debug)]
pub struct ResultSet {
    /// `commissioning.json`.
    pub record: CommissioningRecord,
    /// `controller.toml`.
    pub controller: ControllerFile,
    /// `report.html`, as data.
    pub report: Report,
    /// The data files.
    pub data: DataFiles,
}

impl ResultSet {
    /// The files as (name, contents): `commissioning.json`, `controller.toml`,
    /// `report.html`, then the data files. A controller that
    /// [`ControllerFile::check_plausible`] refuses is an error, not a file.
    pub fn files(&self) -> Result<Vec<(String, Vec<u8>)>> {
        // nothing implausible reaches a drive: the reader's checks, at the writer
        self.controller.check_plausible()?;
        let mut files = vec![
            (
                COMMISSIONING_FILE.to_string(),
                self.record.to_json_text()?.into_bytes(),
            ),
            (
                CONTROLLER_FILE.to_string(),
                self.controller.to_toml()?.into_bytes(),
            ),
            (
                REPORT_FILE.to_string(),
                super::render_html(&self.report)?.into_bytes(),
            ),
        ];
        files.extend(
            self.data
                .texts()
                .into_iter()
                .map(|(n, t)| (n, t.into_bytes())),
        );
        Ok(files)
    }

    /// Write the set to `target`, all files together or none; returns their paths.
    pub fn write(&self, target: &OutputTarget) -> Result<Vec<PathBuf>> {
        target.write(&self.files()?)
    }

    /// The verdict of the set.
    pub fn verdict(&self) -> Option<&Verdict> {
        self.record.verdict.as_ref()
    }

    /// The result of a run on an axis.
    pub fn of_run(run: &Commissioning, origin: &Origin) -> Result<ResultSet> {
        let record = CommissioningRecord::of_run(run, origin);
        let controller = ControllerFile::from_design(
            &run.design,
            &run.friction,
            Some(&run.target_stiffness),
            run.datasheet.torque_max_nm,
            crate::ident::ModelUnits::Torque,
            origin.provenance.clone(),
        )?;
        let tf = run.fit.model.tf(&run.fit.params);
        let labelled: Vec<(String, &MoveResult)> = run
            .moves
            .iter()
            .map(|m| (m.variant.label().to_string(), &m.result))
            .collect();
        let data = DataFiles {
            frf: Some(frf_lines(&run.frf, &tf, run.dead_time.seconds)?),
            loops: Some(loop_data(&run.design)?),
            moves: move_plots(&labelled),
            excitation: Some(excitation_plot(run)),
            friction: Some(FrictionPlot {
                velocity_rad_s: run
                    .friction_points
                    .iter()
                    .map(|p| p.velocity_rad_s)
                    .collect(),
                torque_nm: run
                    .friction_points
                    .iter()
                    .map(|p| p.mean_torque_nm)
                    .collect(),
                viscous_nm_s_per_rad: run.friction.viscous_nm_s_per_rad,
                coulomb_nm: run.friction.coulomb_nm,
            }),
        };
        // the data-sheet model of a simulated physical plant where it was identified
        let datasheet = match origin.axis.simulated_plant() {
            Some(Plant::Physical(p)) => Some(p.linearize(run.identification_position_m)?),
            _ => None,
        };
        let move_rows: Vec<_> = labelled
            .iter()
            .map(|(l, m)| (l.clone(), m.summary.clone()))
            .collect();
        let report = build_report(&ReportInputs {
            kind: ReportKind::Axis,
            record: &record,
            design: &run.design,
            model_tf: &tf,
            data: &data,
            move_rows: &move_rows,
            datasheet_model: datasheet.as_ref(),
            overlays: vec![bootstrap_overlay(run)?],
            absent: Vec::new(),
        })?;
        Ok(ResultSet {
            record,
            controller,
            report,
            data,
        })
    }

    /// The result of a commissioning from a recording.
    pub fn of_recorded(run: &RecordedCommissioning, origin: &Origin) -> Result<ResultSet> {
        let record = CommissioningRecord::of_recorded(run, origin);
        let id = &run.identified;
        let controller = ControllerFile::from_design(
            &run.design,
            &run.friction.clone().unwrap_or_default(),
            None,
            id.torque_max_nm.unwrap_or(f64::NAN),
            id.units,
            origin.provenance.clone(),
        )?;
        let fit = &run.identification.fit;
        let tf = fit.model.tf(&fit.params);
        let data = DataFiles {
            frf: Some(frf_lines(&run.identification.frf, &tf, id.dead_time_s)?),
            loops: Some(loop_data(&run.design)?),
            ..DataFiles::default()
        };
        let report = build_report(&ReportInputs {
            kind: ReportKind::Recorded,
            record: &record,
            design: &run.design,
            model_tf: &tf,
            data: &data,
            move_rows: &[],
            datasheet_model: None,
            overlays: Vec::new(),
            absent: Vec::new(),
        })?;
        Ok(ResultSet {
            record,
            controller,
            report,
            data,
        })
    }

    /// A design saved by the tuning page: the loaded result `base` with the
    /// new design, judged on a simulated move (`sim`, or why it failed).
    pub fn of_tuned(t: &TunedDesign) -> Result<ResultSet> {
        let base = t.base;
        let mut record = base.record.clone();
        record.controller = Some(t.design.summary());
        record.drive_form = Some(crate::design::DriveForm::of(t.design));
        record.guaranteed_margins = t.guaranteed;
        // the measured validation belonged to the old controller
        record.validation = None;
        record.validation_move = None;
        record.verdict = Some(t.verdict.clone());
        record.tuning = Some(Tuning {
            saved_by: "beltune serve".into(),
            model_source: t.source.clone(),
            knobs: crate::record::commissioning::TuningKnobs::of(&t.design.knobs),
            simulated_validation: t.sim.map(|m| m.summary.clone()),
            provenance: Provenance::of_this_process(None),
        });
        let controller = ControllerFile::from_design(
            t.design,
            t.friction,
            t.target_stiffness,
            t.torque_max_nm,
            record.identified.units,
            Provenance::of_this_process(None),
        )?;
        let mut data = base.data.clone();
        data.loops = Some(loop_data(t.design)?);
        data.moves = t
            .sim
            .map(|m| vec![super::build::move_plot(m, &t.move_label)])
            .unwrap_or_default();
        let move_rows: Vec<_> = t
            .sim
            .map(|m| vec![(t.move_label.clone(), m.summary.clone())])
            .unwrap_or_default();
        let tf = FitModel::WithBeltDamping.tf(&record.identified.params());
        let mut absent = Vec::new();
        let sections = [
            (
                data.excitation.is_none(),
                "identification experiment",
                super::data_files::EXCITATION_CSV,
                "written by `beltune commission` on an axis; a record from a CSV file has no excitation trace of its own",
            ),
            (
                data.friction.is_none(),
                "friction",
                super::data_files::FRICTION_CSV,
                "the constant-velocity runs of `beltune commission` on an axis, or `--friction-csv`",
            ),
        ];
        for (missing, section, file, whence) in sections {
            if missing {
                let lacking = if t.from_folder {
                    format!("the loaded folder has no {file}")
                } else {
                    format!("no {file} is known")
                };
                absent.push((section.to_string(), format!("{lacking} ({whence})")));
            }
        }
        if t.sim.is_none() {
            absent.push((
                "validation move".to_string(),
                t.sim_error.clone().unwrap_or_else(|| {
                    format!(
                        "the simulated move with {} kg payload did not complete",
                        t.payload_kg
                    )
                }),
            ));
        }
        let report = build_report(&ReportInputs {
            kind: ReportKind::Tuned {
                source: t.source.clone(),
                payload_kg: t.payload_kg,
                move_label: t.move_label.clone(),
            },
            record: &record,
            design: t.design,
            model_tf: &tf,
            data: &data,
            move_rows: &move_rows,
            datasheet_model: None,
            overlays: Vec::new(),
            absent,
        })?;
        Ok(ResultSet {
            record,
            controller,
            report,
            data,
        })
    }
}

/// What the tuning page saves: a new design on a loaded (or built-in) result.
pub struct TunedDesign<'a> {
    /// The result the design model comes from.
    pub base: &'a ResultFolder,
    /// Whether `base` was read from a folder (the report says which files it lacks).
    pub from_folder: bool,
    /// Where the design model came from, in words.
    pub source: String,
    /// The new design.
    pub design: &'a ControllerDesign,
    /// Its margins over the identification's uncertainty, if computed.
    pub guaranteed: Option<crate::design::robust::GuaranteedMargins>,
    /// The verdict on the simulated move.
    pub verdict: Verdict,
    /// The simulated move, if it completed.
    pub sim: Option<&'a MoveResult>,
    /// Why the simulated move did not complete.
    pub sim_error: Option<String>,
    /// What the move ran on.
    pub move_label: String,
    /// Payload of the move, kg.
    pub payload_kg: f64,
    /// Friction for the feedforward.
    pub friction: &'a FrictionResult,
    /// The belt stiffness the setpoint conversion uses.
    pub target_stiffness: Option<&'a TargetStiffness>,
    /// The drive's torque limit, in the record's units.
    pub torque_max_nm: f64,
}
