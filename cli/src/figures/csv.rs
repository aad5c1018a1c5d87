//! The rows of the sweep as CSV: `figures.csv` (a header, one row per point), a shard's
//! `figures.shard-K-of-N.csv` (the same, after `#` lines that say which shard of which
//! plan it holds), and reading a shard's CSV back for the merge.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Duration;

use cohort_render::{RenderStats, Shard};

use super::plan::{Column, Plan};
use super::plot::PlotRow;

/// One measured point: one row of figures.csv.
pub struct Row {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub config: String,
    pub label: String,
    /// `None` for `normal`, which does not depend on N.
    pub n: Option<u32>,
    /// N of the group the point was measured in (`normal` is measured in every group).
    pub group_n: u32,
    pub column: Column,
    pub interleave: u32,
    pub stats: RenderStats,
    pub rms_percent: f64,
    pub rms_abs: f64,
    pub ratio_vs_normal: f64,
}

impl Row {
    /// RMS error scaled to one path per pixel (Monte Carlo error falls as 1/sqrt(paths)):
    /// an error per path, which does not depend on how fast the paths were completed, and
    /// so not on the GPU's clocks either.
    pub fn rms_at_1spp(&self) -> f64 {
        self.rms_percent * self.stats.paths_per_pixel().sqrt()
    }

    pub fn plot_row(&self) -> PlotRow {
        PlotRow {
            scene: self.scene.clone(),
            config: self.config.clone(),
            n: self.n,
            group_n: self.group_n,
            column: self.column,
            interleave: self.interleave,
            paths_per_pixel: self.stats.paths_per_pixel(),
            rms_percent: self.rms_percent,
        }
    }
}

pub const CSV_HEADER: &str = "scene,width,height,device,config,label,n,rr,compaction,interleave,seed,time_budget_s,\
paths_per_pixel,completed_paths,iterations,rays,paths_per_s,rays_per_s,\
kernel_ms_traverse,kernel_ms_extend,kernel_ms_compact,kernel_ms_total,wall_s,rms_percent,rms_abs,paths_per_s_vs_normal,group_n,rms_at_1spp";

/// The first line of a shard's CSV, which tells it from figures.csv.
const SHARD_FIRST_LINE: &str = "# cohort figures shard: `cohort figures-merge` combines all shards into figures.csv and the plots (docs/FIGURES.md)";
/// The `#` line keys of a shard's CSV that are not the plan's fingerprint.
const SHARD_KEY: &str = "shard";
const REFERENCE_KEY: &str = "reference.";

pub fn shard_file_name(shard: Shard) -> String {
    format!("figures.shard-{}-of-{}.csv", shard.index, shard.count)
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// figures.csv: the header and one line per row.
pub fn figures_csv(rows: &[Row], device: &str, plan: &Plan) -> String {
    let mut out = String::from(CSV_HEADER);
    out.push('\n');
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    for r in rows {
        let s = &r.stats;
        let k = s.kernel;
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{},{},{},{},{},{},{:.4},{},{},{},{:.1},{:.1},{:.3},{:.3},{:.3},{:.3},{:.3},{:.5},{:.6},{:.5},{},{:.5}",
            csv_field(&r.scene),
            r.width,
            r.height,
            csv_field(device),
            r.config,
            csv_field(&r.label),
            r.n.map(|n| n.to_string()).unwrap_or_default(),
            r.column.rr(),
            r.column.compact,
            r.interleave,
            plan.seed,
            plan.time.as_secs_f64(),
            s.paths_per_pixel(),
            s.completed_paths,
            s.iterations,
            s.rays,
            s.paths_per_second(),
            s.rays_per_second(),
            ms(k.traverse),
            ms(k.extend),
            ms(k.compact),
            ms(k.total()),
            s.wall.as_secs_f64(),
            r.rms_percent,
            r.rms_abs,
            r.ratio_vs_normal,
            r.group_n,
            r.rms_at_1spp(),
        );
    }
    out
}

/// A shard's CSV: `#` lines with the shard, the plan's fingerprint and the checksums of
/// the references its rows were measured against (`scene`, checksum), then figures.csv's
/// header and rows.
pub fn shard_csv(
    rows: &[Row],
    device: &str,
    plan: &Plan,
    shard: Shard,
    references: &[(String, String)],
) -> String {
    let mut out = format!("{SHARD_FIRST_LINE}\n# {SHARD_KEY}={shard}\n");
    for (key, value) in plan.fingerprint() {
        let _ = writeln!(out, "# {key}={value}");
    }
    for (scene, checksum) in references {
        let _ = writeln!(out, "# {REFERENCE_KEY}{scene}={checksum}");
    }
    out + &figures_csv(rows, device, plan)
}

/// figures.csv from rows as written in shards' CSVs, in the order given.
pub fn merged_csv<'r>(lines: impl IntoIterator<Item = &'r str>) -> String {
    let mut out = String::from(CSV_HEADER);
    out.push('\n');
    for line in lines {
        out.push_str(line);
        out.push('\n');
    }
    out
}

/// A shard's CSV, read back.
pub struct ShardCsv {
    pub path: PathBuf,
    pub shard: Shard,
    /// The plan's fingerprint (`Plan::fingerprint`), in the file's order.
    pub plan: Vec<(String, String)>,
    /// (scene, checksum) of the references its rows were measured against.
    pub references: Vec<(String, String)>,
    pub rows: Vec<ReadRow>,
}

/// A row of a shard's CSV.
pub struct ReadRow {
    /// Its line in the file (from 1), for messages.
    pub line: usize,
    /// The line as written, which the merged figures.csv repeats.
    pub text: String,
    /// What identifies its point and what the plots draw.
    pub point: PlotRow,
}

/// Reads a shard's CSV as `shard_csv` wrote it; anything else is an error naming the file
/// (and the line).
pub fn read_shard(path: &Path) -> Result<ShardCsv, String> {
    let name = path.display();
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read {name}: {e}"))?;
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l));
    if lines.next().map(|(_, l)| l) != Some(SHARD_FIRST_LINE) {
        return Err(format!(
            "{name}: not a shard's CSV (line 1 is not the first line of the figures.shard-K-of-N.csv that `cohort figures --shard K/N` writes)"
        ));
    }
    let (mut shard, mut plan, mut references) = (None, Vec::new(), Vec::new());
    let mut header_line = None;
    for (line, l) in lines.by_ref() {
        let Some(comment) = l.strip_prefix('#') else {
            header_line = Some((line, l));
            break;
        };
        let (key, value) = comment
            .trim_start()
            .split_once('=')
            .ok_or_else(|| format!("{name}: line {line}: expected `# key=value`, found `{l}`"))?;
        if key == SHARD_KEY {
            shard = Some(Shard::parse(value).map_err(|e| format!("{name}: line {line}: {e}"))?);
        } else if let Some(scene) = key.strip_prefix(REFERENCE_KEY) {
            references.push((scene.to_string(), value.to_string()));
        } else {
            plan.push((key.to_string(), value.to_string()));
        }
    }
    let shard = shard.ok_or_else(|| format!("{name}: has no `# {SHARD_KEY}=K/N` line"))?;
    let (line, header) = header_line.ok_or_else(|| format!("{name}: has no header line"))?;
    if header != CSV_HEADER {
        return Err(format!(
            "{name}: line {line}: the header is not figures.csv's (a CSV of another version of cohort?)"
        ));
    }
    let columns: Vec<&str> = CSV_HEADER.split(',').collect();
    let mut rows = Vec::new();
    for (line, l) in lines.filter(|(_, l)| !l.is_empty()) {
        let at = |e: String| format!("{name}: line {line}: {e}");
        let fields = split_line(l).map_err(at)?;
        if fields.len() != columns.len() {
            return Err(at(format!(
                "{} fields, but the header has {}",
                fields.len(),
                columns.len()
            )));
        }
        let field = |key: &str| {
            let i = columns.iter().position(|c| *c == key).expect("a column");
            fields[i].as_str()
        };
        let parse = |key: &str| -> Result<f64, String> {
            field(key)
                .parse::<f64>()
                .map_err(|_| at(format!("`{key}` is `{}`, not a number", field(key))))
        };
        let whole = |key: &str| -> Result<u32, String> {
            field(key)
                .parse::<u32>()
                .map_err(|_| at(format!("`{key}` is `{}`, not a whole number", field(key))))
        };
        let column = Column::from_csv(field("rr"), field("compaction")).ok_or_else(|| {
            at(format!(
                "no column of the figures has rr `{}` and compaction `{}`",
                field("rr"),
                field("compaction")
            ))
        })?;
        let point = PlotRow {
            scene: field("scene").to_string(),
            config: field("config").to_string(),
            n: match field("n") {
                "" => None,
                _ => Some(whole("n")?),
            },
            group_n: whole("group_n")?,
            column,
            interleave: whole("interleave")?,
            paths_per_pixel: parse("paths_per_pixel")?,
            rms_percent: parse("rms_percent")?,
        };
        rows.push(ReadRow {
            line,
            text: l.to_string(),
            point,
        });
    }
    Ok(ShardCsv {
        path: path.to_path_buf(),
        shard,
        plan,
        references,
        rows,
    })
}

/// The fields of a CSV line: quoted fields may hold commas and doubled quotes.
fn split_line(line: &str) -> Result<Vec<String>, String> {
    let mut fields = Vec::new();
    let (mut field, mut quoted) = (String::new(), false);
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                chars.next();
                field.push('"');
            }
            '"' => quoted = !quoted,
            ',' if !quoted => fields.push(std::mem::take(&mut field)),
            c => field.push(c),
        }
    }
    if quoted {
        return Err("a quoted field is not closed".into());
    }
    fields.push(field);
    Ok(fields)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_quotes_fields_with_commas() {
        assert_eq!(
            csv_field("llvmpipe (LLVM 15, 256 bits)"),
            "\"llvmpipe (LLVM 15, 256 bits)\""
        );
        assert_eq!(csv_field("warp_rr (NO)"), "warp_rr (NO)");
    }

    #[test]
    fn split_line_reads_back_quoted_fields() {
        let fields = ["a", "b, \"c\"", "", "warp_rr (NO)"];
        let line = fields.map(csv_field).join(",");
        assert_eq!(split_line(&line).unwrap(), fields);
        assert!(split_line("a,\"b").is_err());
    }
}
