//! The short form of the whole-mission agreement harness, in the test command.

use stx_agreement::campaign::{CampaignOptions, run, specs, summarise};

fn keep_out() -> Option<(String, String)> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../config/keep-out/sample.geojson");
    let text = std::fs::read_to_string(&path).expect("the shipped zones");
    Some((path.display().to_string(), text))
}

#[test]
fn the_station_agrees_with_the_drone_over_whole_missions() {
    let options = CampaignOptions::short();
    let specs = specs(&options, keep_out()).expect("campaign");
    let results = run(&specs, 2, &|r| match r {
        Ok(r) => eprintln!("{}", serde_json::to_string(r).unwrap_or_default()),
        Err(f) => eprintln!("FAILED {f:?}"),
    });
    let summary = summarise(&results);
    eprintln!(
        "{}",
        serde_json::to_string_pretty(&summary).unwrap_or_default()
    );
    let unmet: Vec<_> = summary.goals.iter().filter(|g| !g.met).collect();
    assert!(unmet.is_empty(), "goals not met: {unmet:#?}");
}
