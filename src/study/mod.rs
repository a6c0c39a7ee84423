//! Study and comparison tools: `umbra bench` (each method's frame and phases, timed with
//! warm-up, median and spread), `umbra compare` (every method on one scene, against the
//! ray-cast reference, as an HTML report), `umbra scale` (cost against a scene parameter, as
//! CSV and plots), `umbra trace` (one scanline, step by step), `umbra explore` (the same,
//! drawn in a browser page), and false-colour images of the per-pixel counters.

pub mod bench;
pub mod compare;
pub mod explore;
pub mod map_errors;
#[cfg(feature = "plots")]
mod plot;
mod quiet;
pub mod scale;
pub mod trace;

/// What a measurement was taken with, recorded in every report: the program, the machine,
/// the date and the options.
#[derive(Debug, Clone, serde::Serialize)]
pub struct About {
    /// umbra's version.
    pub umbra: &'static str,
    /// When, in UTC (`YYYY-MM-DD HH:MM:SS`).
    pub date_utc: String,
    /// The CPU's model name (from `/proc/cpuinfo`; empty where the system does not say).
    pub cpu: String,
    /// Logical cores available to the process.
    pub cores: usize,
    /// Threads the engine renders with.
    pub threads: usize,
    /// Operating system and architecture.
    pub os: String,
    /// The options the measurement used, as the library sees them.
    pub options: String,
}

impl About {
    /// The program and machine now, with `options` described.
    pub fn now(options: impl Into<String>) -> About {
        let cpu = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|t| t.lines().find(|l| l.starts_with("model name")).map(|l| l.to_owned()))
            .and_then(|l| l.split_once(':').map(|(_, v)| v.trim().to_owned()))
            .unwrap_or_default();
        let secs = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_secs());
        About {
            umbra: env!("CARGO_PKG_VERSION"),
            date_utc: utc(secs),
            cpu,
            cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
            threads: rayon::current_num_threads(),
            os: format!("{} {}", std::env::consts::OS, std::env::consts::ARCH),
            options: options.into(),
        }
    }
}

impl About {
    /// One HTML paragraph saying what a report was measured with.
    pub(crate) fn html(&self) -> String {
        let cpu = if self.cpu.is_empty() { "CPU not reported" } else { &self.cpu };
        format!(
            "<p class=\"about\">umbra {}, {} UTC; {} ({} cores, {} render threads, {}). Options: {}.</p>\n",
            self.umbra,
            self.date_utc,
            escape(cpu),
            self.cores,
            self.threads,
            escape(&self.os),
            escape(&self.options)
        )
    }
}

/// A method's name as HTML, linked to its page in the project's `docs/algorithms/` (the
/// checkout this program was built from) by a path relative to the report in `dir`; the
/// bare name where that page is not on this machine, or the method has none.
pub(crate) fn method_link(name: &str, dir: &std::path::Path) -> String {
    // A paper path's label links its stage's page.
    let stage = name.strip_suffix(" (paper)").unwrap_or(name);
    let page = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/algorithms").join(format!("{stage}.md"));
    let href = page.canonicalize().ok().zip(dir.canonicalize().ok()).map(|(page, dir)| relative(&page, &dir));
    match href {
        Some(href) => format!("<a href=\"{}\">{}</a>", escape(&href), escape(name)),
        None => escape(name),
    }
}

/// `to` as a path relative to the directory `from` (both absolute), with `/` separators.
fn relative(to: &std::path::Path, from: &std::path::Path) -> String {
    let (to, from): (Vec<_>, Vec<_>) = (to.components().collect(), from.components().collect());
    let common = to.iter().zip(&from).take_while(|(a, b)| a == b).count();
    let up = std::iter::repeat_n("..".to_string(), from.len() - common);
    let down = to[common..].iter().map(|c| c.as_os_str().to_string_lossy().into_owned());
    up.chain(down).collect::<Vec<_>>().join("/")
}

/// `s` made safe inside HTML text and attributes.
pub(crate) fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// Seconds since 1970 as a UTC date and time (the civil calendar from a day count, after
/// Hinnant's `civil_from_days`).
fn utc(secs: u64) -> String {
    let (days, rest) = ((secs / 86_400) as i64, secs % 86_400);
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02} {:02}:{:02}:{:02}", rest / 3600, rest % 3600 / 60, rest % 60)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_paths_climb_to_the_common_folder() {
        use std::path::Path;
        assert_eq!(
            relative(Path::new("/r/docs/algorithms/crow.md"), Path::new("/r/docs/compare/s1")),
            "../../algorithms/crow.md"
        );
        assert_eq!(relative(Path::new("/r/docs/x.md"), Path::new("/r/docs")), "x.md");
    }

    #[test]
    fn method_links_point_at_pages_that_exist() {
        let here = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/compare");
        assert_eq!(method_link("crow", &here), "<a href=\"../algorithms/crow.md\">crow</a>");
        assert_eq!(method_link("none", &here), "none");
        assert_eq!(method_link("crow (paper)", &here), "<a href=\"../algorithms/crow.md\">crow (paper)</a>");
    }

    #[test]
    fn utc_dates_are_the_calendar_s() {
        assert_eq!(super::utc(0), "1970-01-01 00:00:00");
        assert_eq!(super::utc(951_782_400), "2000-02-29 00:00:00");
        assert_eq!(super::utc(1_795_000_000), "2026-11-18 11:06:40");
    }
}
