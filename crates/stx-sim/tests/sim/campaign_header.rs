//! A campaign's header names the vehicle files it was given, and only those.

use stx_sim::montecarlo::{CampaignHeader, MonteCarloConfig};

/// The header names the vehicle files only when a campaign was given them, so that a part
/// written before the fields existed still reads as the shipped stack planned with the
/// shipped table, and parts planned with different files are different campaigns.
#[test]
fn the_header_names_vehicle_files_only_when_given_and_parts_without_them_still_read() {
    let plain = CampaignHeader::of(&MonteCarloConfig::default());
    let written = serde_json::to_value(&plain).expect("serialises");
    assert!(written.get("vehicle").is_none() && written.get("guidance_vehicle").is_none());
    let read: CampaignHeader = serde_json::from_value(written).expect("reads");
    assert_eq!(read, plain);
    let named = CampaignHeader::of(&MonteCarloConfig {
        vehicle_name: Some("identified.toml".into()),
        guidance_vehicle_name: Some("identified.toml".into()),
        ..MonteCarloConfig::default()
    });
    let written = serde_json::to_value(&named).expect("serialises");
    assert_eq!(written["guidance_vehicle"], "identified.toml");
    let read: CampaignHeader = serde_json::from_value(written).expect("reads");
    assert_eq!(read, named);
    assert_ne!(named, plain);
}
