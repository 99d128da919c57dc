//! The printer panel (SPEC §8, §9): list ports, print the current design on one (the serial link
//! runs on a background thread and talks to the ECS through channels), pause, resume, cancel,
//! emergency stop; progress, temperatures and the printer's messages; the replay nozzle in the
//! 3D view follows the line being printed. Try it against `clayloft fake-printer`.

use std::collections::VecDeque;
use std::sync::Mutex;
use std::sync::mpsc::{Receiver, Sender as Tx, channel};
use std::time::Instant;

use bevy::prelude::*;
use bevy_egui::{EguiContexts, EguiPrimaryContextPass, egui};
use clayloft_model::DesignDoc;
use clayloft_model::background::{Background, Stopped};
use clayloft_replay::{Replay, ReplayPath};
use clayloft_serial::line::strip;
use clayloft_serial::link::{list_ports, open_port, run_job};
use clayloft_serial::reply::Temperatures;
use clayloft_serial::sender::State;
use clayloft_serial::{Event, Sender, SenderConfig};

/// What the panel asks the link thread to do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Control {
    Pause,
    Resume,
    Cancel,
    EmergencyStop,
}

/// What the link thread reports.
#[derive(Debug, Clone, PartialEq)]
pub enum LinkEvent {
    Event(Event),
    /// The job ended: finished, or why not.
    Ended(Result<(), String>),
}

/// A job running on its thread.
pub struct Job {
    control: Tx<Control>,
    events: Mutex<Receiver<LinkEvent>>,
    /// Toolpath point of each stripped G-code command (`None` before the first move).
    point_of_command: Vec<usize>,
    paused: bool,
}

/// The printer panel's state.
#[derive(Resource, Default)]
pub struct PrinterPanel {
    pub port: String,
    pub baud: u32,
    pub ports: Vec<String>,
    pub job: Option<Job>,
    pub done: usize,
    pub total: usize,
    pub started: Option<Instant>,
    /// The job's planned printing time (the core's motion planner), s.
    pub planned_s: f64,
    /// Transmission errors the printer caught and resends recovered, this job.
    pub recovered: u64,
    pub temperatures: Option<Temperatures>,
    pub messages: VecDeque<String>,
    pub status: Option<(String, bool)>,
    /// A job being prepared on its own thread ([`prepare_job`]): the program written and
    /// checked, the port opened. The window stays live meanwhile (the benchmark vase's program
    /// takes tens of milliseconds to write and check, a port may take longer to open).
    pub preparing: Option<Background<Result<(Job, f64), String>>>,
}

pub struct PrinterPlugin;

impl Plugin for PrinterPlugin {
    fn build(&self, app: &mut App) {
        app.insert_resource(PrinterPanel {
            baud: 115_200,
            ports: list_ports(),
            ..default()
        })
        .add_systems(Update, pump_link_events)
        .add_systems(
            EguiPrimaryContextPass,
            draw_printer_window.in_set(clayloft_ui::UiSystems::Windows),
        );
    }
}

/// [`start_job`] with the job's planned printing time (the core's motion planner), s: what the
/// panel runs on a thread of its own when "Print design" is pressed.
pub fn prepare_job(
    design: &clayloft_core::Design,
    job: &clayloft_core::PrintJob,
    port: &str,
    baud: u32,
) -> Result<(Job, f64), String> {
    let started = start_job(design, job, port, baud)?;
    let planned = clayloft_core::gcode::summarize(design, job).estimated_time_s;
    Ok((started, planned))
}

/// Starts printing `job` (the session's, for `design`) on `port`: the core writes the program
/// with each line's path point, checks it as `clayloft gcode` does (a program past the
/// printer's limits is refused), and a background thread streams it.
pub fn start_job(
    design: &clayloft_core::Design,
    job: &clayloft_core::PrintJob,
    port: &str,
    baud: u32,
) -> Result<Job, String> {
    let program = clayloft_core::gcode::program(design, job).map_err(|e| e.to_string())?;
    // Right first time: a program that breaks a limit of this printer is not started.
    clayloft_core::export::verify_program(design, &program.text)
        .map_err(|e| format!("not printed: the design {e}"))?;
    let (cmds, point_of_command): (Vec<String>, Vec<usize>) = program
        .text
        .lines()
        .zip(&program.point_of_line)
        .filter_map(|(line, &point)| strip(line).map(|c| (c.to_string(), point as usize)))
        .unzip();
    // Cancel sends this in place of the rest of the job: stop extruding, lift clear, park.
    let cancel = clayloft_serial::line::commands(
        &clayloft_core::gcode::cancel_gcode(design, job).map_err(|e| e.to_string())?,
    );
    let mut sender =
        Sender::new(cmds, SenderConfig::default(), Instant::now()).map_err(|e| e.to_string())?;
    let mut link = open_port(port, baud)?;
    let (control_tx, control_rx) = channel::<Control>();
    let (event_tx, event_rx) = channel::<LinkEvent>();
    std::thread::spawn(move || {
        let tx = event_tx.clone();
        run_job(
            link.as_mut(),
            &mut sender,
            |ev| {
                let _ = tx.send(LinkEvent::Event(ev.clone()));
            },
            |s| {
                while let Ok(c) = control_rx.try_recv() {
                    match c {
                        Control::Pause => s.pause(),
                        Control::Resume => s.resume(),
                        Control::Cancel => s.cancel_with(cancel.clone()),
                        Control::EmergencyStop => s.emergency_stop(),
                    }
                }
            },
        );
        let end = match sender.state() {
            State::Finished => Ok(()),
            State::Failed(why) => Err(why.clone()),
            State::Cancelled => Err("cancelled".into()),
            other => Err(format!("{other:?}")),
        };
        let _ = event_tx.send(LinkEvent::Ended(end));
    });
    Ok(Job {
        control: control_tx,
        events: Mutex::new(event_rx),
        point_of_command,
        paused: false,
    })
}

/// Brings the link thread's news into the panel, and moves the replay nozzle to the line being
/// printed.
fn pump_link_events(
    mut panel: ResMut<PrinterPanel>,
    mut replay: ResMut<Replay>,
    path: Res<ReplayPath>,
    redraw: Option<ResMut<Messages<bevy::window::RequestRedraw>>>,
) {
    // While a job is being prepared, frames are asked for so that it is polled (the app draws
    // on input only).
    if take_prepared_job(&mut panel)
        && let Some(mut redraw) = redraw
    {
        redraw.write(bevy::window::RequestRedraw);
    }
    let Some(job) = &panel.job else { return };
    let news: Vec<LinkEvent> = match job.events.lock() {
        Ok(rx) => rx.try_iter().collect(),
        Err(_) => return,
    };
    for n in news {
        match n {
            LinkEvent::Event(Event::Progress { done, total }) => {
                panel.done = done;
                panel.total = total;
                let point = panel
                    .job
                    .as_ref()
                    .and_then(|j| j.point_of_command.get(done.saturating_sub(1)).copied())
                    .unwrap_or(0);
                replay.active = true;
                replay.playing = false;
                replay.time_s = path.timeline.time_of(point);
            }
            LinkEvent::Event(Event::Temperatures(t)) => panel.temperatures = Some(t),
            LinkEvent::Event(Event::Message(m)) => {
                panel.messages.push_back(m);
                while panel.messages.len() > 200 {
                    panel.messages.pop_front();
                }
            }
            LinkEvent::Event(Event::Recovered { count, .. }) => panel.recovered = count,
            LinkEvent::Event(Event::PrinterError(m)) => {
                panel
                    .messages
                    .push_back(format!("printer error (the job goes on): {m}"));
                while panel.messages.len() > 200 {
                    panel.messages.pop_front();
                }
            }
            LinkEvent::Event(_) => {}
            LinkEvent::Ended(r) => {
                panel.status = Some(match r {
                    Ok(()) => (format!("printed all {} lines", panel.total), false),
                    Err(why) => (why, true),
                });
                panel.job = None;
            }
        }
    }
}

/// Takes the job prepared on its thread, once it is: started, or why not. Whether one is still
/// being prepared.
fn take_prepared_job(panel: &mut PrinterPanel) -> bool {
    let Some(preparing) = &mut panel.preparing else {
        return false;
    };
    let Some(result) = preparing.poll() else {
        return true;
    };
    panel.preparing = None;
    match result {
        Ok(Ok((job, planned))) => {
            panel.planned_s = planned;
            panel.recovered = 0;
            panel.job = Some(job);
            panel.done = 0;
            panel.started = Some(Instant::now());
            panel.status = Some((format!("printing on {}", panel.port), false));
        }
        Ok(Err(e)) => panel.status = Some((e, true)),
        Err(Stopped) => {
            panel.status = Some(("the program could not be prepared (stopped)".into(), true))
        }
    }
    false
}

fn draw_printer_window(
    mut contexts: EguiContexts,
    mut panel: ResMut<PrinterPanel>,
    doc: Option<Res<DesignDoc>>,
    engine: Res<clayloft_model::Engine>,
) -> Result {
    let ctx = contexts.ctx_mut()?.clone();
    if panel.job.is_some() {
        // The link thread's news arrives on a channel: keep frames coming while a job streams
        // (the app otherwise sleeps until the next input).
        ctx.request_repaint();
    }
    clayloft_ui::tool_window(&ctx, PRINTER_WINDOW, clayloft_ui::Corner::TopLeft, false)
        .show(&ctx, |ui| {
            ui.label(egui::RichText::new("Streams the design's G-code line by line (Marlin protocol: numbered lines, checksums, resends). Try it on `clayloft fake-printer`.").small().weak());
            ui.horizontal(|ui| {
                ui.label("Port");
                egui::ComboBox::from_id_salt("ports").selected_text(panel.port.clone()).show_ui(ui, |ui| {
                    let ports = panel.ports.clone();
                    for p in ports {
                        ui.selectable_value(&mut panel.port, p.clone(), p);
                    }
                });
                if ui.small_button("↻").on_hover_text("list the ports again").clicked() {
                    panel.ports = list_ports();
                }
            });
            ui.horizontal(|ui| {
                ui.label("or path");
                ui.text_edit_singleline(&mut panel.port);
            });
            ui.horizontal(|ui| {
                ui.label("Baud");
                ui.add(egui::DragValue::new(&mut panel.baud).range(9600..=1_000_000));
            });
            let running = panel.job.is_some() || panel.preparing.is_some();
            ui.horizontal(|ui| {
                if ui.add_enabled(!running && !panel.port.is_empty(), egui::Button::new("⏵ Print design")).clicked()
                    && let Some(doc) = &doc
                {
                    match engine.current_job(&doc.design) {
                        Ok(job) => {
                            let (design, port, baud) = (doc.design.clone(), panel.port.clone(), panel.baud);
                            panel.status = Some((format!("checking the program for this printer, then {port} …"), false));
                            panel.preparing = Some(Background::start(move || prepare_job(&design, &job, &port, baud)));
                        }
                        Err(e) => panel.status = Some((e, true)),
                    }
                }
                let port = panel.port.clone();
                let mut now_paused = None;
                if let Some(job) = &mut panel.job {
                    let label = if job.paused { "resume" } else { "pause" };
                    if ui.button(label).clicked() {
                        let _ = job.control.send(if job.paused { Control::Resume } else { Control::Pause });
                        job.paused = !job.paused;
                        now_paused = Some(job.paused);
                    }
                    if ui.button("cancel").clicked() {
                        let _ = job.control.send(Control::Cancel);
                    }
                    if ui.button(egui::RichText::new("EMERGENCY STOP").color(egui::Color32::RED)).on_hover_text("M112: the printer halts at once").clicked() {
                        let _ = job.control.send(Control::EmergencyStop);
                    }
                }
                if let Some(paused) = now_paused {
                    let what = if paused { "paused" } else { "printing" };
                    panel.status = Some((format!("{what} on {port}"), false));
                }
            });
            if panel.total > 0 {
                let f = panel.done as f32 / panel.total as f32;
                // From the planned time, not the clock: a pause does not make it grow, and there is
                // none once the job has ended.
                let left = (panel.job.is_some() && panel.planned_s > 0.0)
                    .then(|| panel.planned_s * (1.0 - f64::from(f)));
                ui.add(egui::ProgressBar::new(f).text(format!(
                    "{}/{} lines{}",
                    panel.done,
                    panel.total,
                    left.map(|e| format!(", about {} left", clayloft_core::gcode::format_duration(e))).unwrap_or_default()
                )));
            }
            if panel.recovered > 0 {
                ui.label(format!(
                    "{} lines resent (transmission errors the printer caught; recovered)",
                    panel.recovered
                ))
                .on_hover_text("The printer found a line garbled on the way (its checksum or number did not match) and asked for it again: normal on long USB cables, harmless once resent.");
            }
            if let Some(t) = panel.temperatures {
                let show = |v: Option<(f64, f64)>| v.map(|(a, b)| format!("{a:.1}/{b:.0} °C")).unwrap_or("–".into());
                ui.label(format!("nozzle {}   bed {}", show(t.tool), show(t.bed)));
            }
            if let Some((m, err)) = &panel.status {
                let c = if *err { egui::Color32::from_rgb(255, 90, 90) } else { egui::Color32::from_rgb(150, 220, 150) };
                ui.colored_label(c, m);
            }
            egui::ScrollArea::vertical().max_height(120.0).stick_to_bottom(true).show(ui, |ui| {
                for m in &panel.messages {
                    ui.monospace(m);
                }
            });
        });
    clayloft_ui::toggle_on_title_click(&ctx, PRINTER_WINDOW, false);
    Ok(())
}

/// The window's title.
const PRINTER_WINDOW: &str = "Printer";

#[cfg(test)]
mod tests {
    use super::*;

    /// The fake printer on one end of a pseudo-terminal pair: the other end's name, and the
    /// thread serving it (its log once the job has ended).
    fn fake_printer() -> (
        String,
        std::thread::JoinHandle<clayloft_serial::fake::FakePrinter>,
    ) {
        use clayloft_serial::fake::{FakePrinter, Faults};
        use clayloft_serial::link::serve_fake;
        use serialport::{SerialPort, TTYPort};
        let (mut master, slave) = TTYPort::pair().unwrap();
        master
            .set_timeout(std::time::Duration::from_millis(5))
            .unwrap();
        let name = slave.name().unwrap();
        drop(slave);
        let fake = std::thread::spawn(move || {
            serve_fake(
                &mut master as &mut dyn SerialPort,
                FakePrinter::new(Faults::default()),
                |_| false,
            )
        });
        (name, fake)
    }

    /// Right first time: the petal vase with a start G-code that lays a purge line and travels
    /// to the vessel is not one continuous path (`clayloft gcode` refuses it), so printing it
    /// does not start, nor open the port.
    #[test]
    fn a_program_past_the_printers_limits_is_not_started() {
        let bowl = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../assets/designs/petal-vase.toml");
        let mut design = clayloft_core::load::load_design_using(&bowl, None)
            .unwrap()
            .design;
        design.printer.start_gcode =
            Some("G28\nG1 X5 Y5 Z0.3 F3000\nG1 X60 Y5 Z5 E10 F1000\n".into());
        let job = clayloft_core::run(&design).unwrap();
        let e = start_job(&design, &job, "/nonexistent/port", 115_200)
            .err()
            .expect("refused");
        assert!(
            e.starts_with(
                "not printed: the design does not print on this printer (the paper's printer)"
            ) && e.contains("not one continuous path"),
            "{e}"
        );
    }

    /// A cylinder 40 mm across, `height` mm tall, `samples` points a layer, and its job.
    fn cylinder(height: f64, samples: usize) -> (clayloft_core::Design, clayloft_core::PrintJob) {
        let design = clayloft_core::load::parse_design(&format!(
            "version = 1\n[shape]\nheight = {height}\nsamples = {samples}\nlower = {{ type = \"circle\", radius = 20.0 }}\nupper = {{ type = \"circle\", radius = 20.0 }}\n"
        ))
        .unwrap();
        let print = clayloft_core::run(&design).unwrap();
        (design, print)
    }

    /// "Print design" prepares the job on a thread of its own: the panel takes it once it is
    /// ready (printing, with the planned time), or says why not (the port missing); until then
    /// it has no job and says it is still preparing (so that frames are asked for).
    #[test]
    fn a_job_is_prepared_off_the_ui_thread_and_taken_when_ready() {
        let (design, print) = cylinder(5.0, 24);
        let take = |port: String| {
            let (d, p) = (design.clone(), print.clone());
            let (gate_tx, gate) = std::sync::mpsc::channel::<()>();
            let mut panel = PrinterPanel {
                port: port.clone(),
                preparing: Some(Background::start(move || {
                    gate.recv().unwrap();
                    prepare_job(&d, &p, &port, 115_200)
                })),
                ..PrinterPanel::default()
            };
            assert!(take_prepared_job(&mut panel), "still preparing");
            assert!(panel.job.is_none());
            gate_tx.send(()).unwrap();
            while take_prepared_job(&mut panel) {
                std::thread::sleep(std::time::Duration::from_millis(1));
            }
            assert!(panel.preparing.is_none());
            panel
        };
        let (name, fake) = fake_printer();
        let mut panel = take(name.clone());
        assert_eq!(panel.status, Some((format!("printing on {name}"), false)));
        assert!(panel.planned_s > 0.0);
        let job = panel.job.take().expect("started");
        let _ = job.control.send(Control::EmergencyStop);
        drop(job);
        drop(fake);
        let panel = take("/nonexistent/port".into());
        assert!(panel.job.is_none());
        assert!(
            panel
                .status
                .as_ref()
                .is_some_and(|(m, error)| *error && m.contains("/nonexistent/port")),
            "{:?}",
            panel.status
        );
    }

    #[test]
    fn a_job_streams_to_a_fake_printer_on_its_thread() {
        let (name, fake) = fake_printer();
        let (design, print) = cylinder(5.0, 24);
        let job = start_job(&design, &print, &name, 115_200).unwrap();
        // Every command carries its path point from the core's writer: in order, to the end.
        let points = job.point_of_command.clone();
        assert!(points.windows(2).all(|w| w[0] <= w[1]));
        assert_eq!(*points.last().unwrap(), print.toolpath.points.len() - 1);
        let rx = job.events.lock().unwrap();
        let end = loop {
            match rx
                .recv_timeout(std::time::Duration::from_secs(20))
                .expect("no hang")
            {
                LinkEvent::Ended(r) => break r,
                LinkEvent::Event(_) => {}
            }
        };
        assert_eq!(end, Ok(()));
        drop(rx);
        drop(job);
        let printer = fake.join().unwrap();
        assert!(printer.log.iter().filter(|c| c.starts_with("G1 ")).count() > 24 * 5);
        // The printer executed exactly the commands the index covers; the k-th G1 it ran is
        // the move to path point k.
        assert_eq!(printer.log.len(), points.len());
        let mut k = 0;
        for (cmd, &p) in printer.log.iter().zip(&points) {
            if cmd.starts_with("G1 ") {
                k += 1;
                assert_eq!(p, k, "{cmd}");
            }
        }
    }

    #[test]
    fn cancel_lifts_and_parks_on_the_fake_printer() {
        let (name, fake) = fake_printer();
        let (design, print) = cylinder(30.0, 60);
        let job = start_job(&design, &print, &name, 115_200).unwrap();
        let rx = job.events.lock().unwrap();
        let mut cancelled = false;
        let end = loop {
            match rx
                .recv_timeout(std::time::Duration::from_secs(20))
                .expect("no hang")
            {
                LinkEvent::Ended(r) => break r,
                LinkEvent::Event(Event::Progress { done, .. }) if done > 200 && !cancelled => {
                    job.control.send(Control::Cancel).unwrap();
                    cancelled = true;
                }
                LinkEvent::Event(_) => {}
            }
        };
        assert_eq!(end, Err("cancelled".into()));
        drop(rx);
        drop(job);
        let printer = fake.join().unwrap();
        let expected = clayloft_serial::line::commands(
            &clayloft_core::gcode::cancel_gcode(&design, &print).unwrap(),
        );
        // The printer ran part of the path, then the cancel sequence, and nothing else.
        assert!(printer.log.len() < 1000, "{}", printer.log.len());
        assert_eq!(
            printer.log[printer.log.len() - expected.len()..],
            expected[..]
        );
        let lift = expected.iter().find(|c| c.starts_with("G0 Z")).unwrap();
        let z: f64 = lift[4..].split(' ').next().unwrap().parse().unwrap();
        assert!(z > 30.0, "{lift}");
    }
}
