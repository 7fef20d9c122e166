//! The live method-comparison table: rows arrive from the worker as they are measured; clicking a column
//! header sorts by it.

use crate::tracer::compare::CompareRow;

/// Sortable columns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Column {
    Method,
    Tile,
    Fps,
    Mrays,
    N,
    I,
    Culled,
}

/// The comparison's rows and how they are shown.
pub struct CompareTable {
    pub(super) rows: Vec<CompareRow>,
    total: usize,
    running: bool,
    open: bool,
    sort: Column,
    descending: bool,
    cancel: bool,
}

impl Default for CompareTable {
    fn default() -> Self {
        Self {
            rows: Vec::new(),
            total: 0,
            running: false,
            open: false,
            sort: Column::Fps,
            descending: true,
            cancel: false,
        }
    }
}

impl CompareTable {
    /// Clears the table for a new run.
    pub fn start(&mut self) {
        self.rows.clear();
        self.total = 0;
        self.running = true;
        self.open = true;
        self.cancel = false;
    }

    /// Adds a measured row.
    pub fn add(&mut self, row: CompareRow, total: usize) {
        self.rows.push(row);
        self.total = total;
    }

    /// Marks the run finished.
    pub fn finish(&mut self) {
        self.running = false;
    }

    /// True while the worker is measuring.
    pub fn running(&self) -> bool {
        self.running
    }

    /// True once, after the user asked to cancel.
    pub fn take_cancel(&mut self) -> bool {
        std::mem::take(&mut self.cancel)
    }

    fn sorted(&self) -> Vec<&CompareRow> {
        let mut v: Vec<&CompareRow> = self.rows.iter().collect();
        let key = |r: &CompareRow| -> f64 {
            match self.sort {
                Column::Method => 0.0,
                Column::Tile => f64::from(r.tile),
                Column::Fps => r.fps,
                Column::Mrays => r.mrays,
                Column::N => r.n,
                Column::I => r.i,
                Column::Culled => r.culled_pct,
            }
        };
        v.sort_by(|a, b| {
            let o = if self.sort == Column::Method {
                a.method.name().cmp(b.method.name()).then(a.tile.cmp(&b.tile))
            } else {
                key(a).total_cmp(&key(b))
            };
            if self.descending { o.reverse() } else { o }
        });
        v
    }

    /// The rows in the current order as a markdown table, for pasting into notes and issues.
    pub fn markdown(&self) -> String {
        let mut s = String::from(
            "| method | tile | FPS | ms | Mrays/s | N | I | culled % |\n|---|---:|---:|---:|---:|---:|---:|---:|\n",
        );
        for r in self.sorted() {
            let (m, t) = (r.method.name(), r.tile);
            s.push_str(&format!(
                "| {m} | {t}x{t} | {:.1} | {:.2} | {:.2} | {:.2} | {:.2} | {:.1} |\n",
                r.fps, r.ms, r.mrays, r.n, r.i, r.culled_pct
            ));
        }
        s
    }

    /// The floating window with the table; returns the rectangle it covers, when shown.
    pub fn window(&mut self, ctx: &egui::Context) -> Option<egui::Rect> {
        if !self.open {
            return None;
        }
        let mut open = self.open;
        let shown =
            egui::Window::new("Compare methods").open(&mut open).resizable(true).default_width(460.0).show(ctx, |ui| {
                if self.running {
                    ui.horizontal(|ui| {
                        ui.spinner();
                        ui.label(format!("measuring {} of {}...", self.rows.len() + 1, self.total.max(1)));
                        if ui.button("Cancel").clicked() {
                            self.cancel = true;
                        }
                    });
                }
                ui.small(format!(
                    "median of {} frames per row after a warm-up; N and I per 2x2 packet as in thesis Tables 4.1-4.5",
                    crate::tracer::compare::TIMED_FRAMES
                ));
                if !self.rows.is_empty() && ui.button("Copy as markdown").clicked() {
                    ui.ctx().copy_text(self.markdown());
                }
                let best = self.rows.iter().map(|r| r.fps).fold(0.0, f64::max);
                egui::Grid::new("compare").striped(true).num_columns(7).show(ui, |ui| {
                    for (c, name) in [
                        (Column::Method, "method"),
                        (Column::Tile, "tile"),
                        (Column::Fps, "FPS"),
                        (Column::Mrays, "Mrays/s"),
                        (Column::N, "N"),
                        (Column::I, "I"),
                        (Column::Culled, "culled %"),
                    ] {
                        let arrow = if self.sort == c { if self.descending { " v" } else { " ^" } } else { "" };
                        if ui.button(format!("{name}{arrow}")).clicked() {
                            if self.sort == c {
                                self.descending = !self.descending;
                            } else {
                                self.sort = c;
                                self.descending = !matches!(c, Column::Method | Column::N | Column::I);
                            }
                        }
                    }
                    ui.end_row();
                    for r in self.sorted() {
                        let label = r.method.name();
                        if r.fps == best {
                            ui.strong(label);
                        } else {
                            ui.label(label);
                        }
                        ui.monospace(format!("{0}x{0}", r.tile));
                        ui.monospace(format!("{:.1}", r.fps));
                        ui.monospace(format!("{:.2}", r.mrays));
                        ui.monospace(format!("{:.2}", r.n));
                        ui.monospace(format!("{:.2}", r.i));
                        ui.monospace(format!("{:.1}", r.culled_pct));
                        ui.end_row();
                    }
                });
            });
        self.open = open;
        shown.map(|r| r.response.rect)
    }
}
