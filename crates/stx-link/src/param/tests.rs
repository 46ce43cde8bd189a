//! The ground and vehicle sides together: list, read and set through both.

use std::time::Duration;

use mavlink::dialects::common::MavMessage;

use super::*;

fn table() -> ParamTable {
    ParamTable::new(
        1,
        1,
        vec![
            ParamSpec::new("HDG_KP", 0.8, 0.0, 5.0, "heading P gain, 1/s"),
            ParamSpec::new("HDG_KD", 0.1, 0.0, 2.0, "heading D gain, s"),
            ParamSpec::new("FLARE_ALT_M", 8.0, 0.0, 50.0, "flare height, m"),
        ],
    )
    .expect("valid table")
}

fn pump(cl: &mut ParamClient, tb: &mut ParamTable) {
    loop {
        let mut moved = false;
        while let Some(m) = cl.poll_transmit() {
            tb.handle_message(&m);
            moved = true;
        }
        while let Some(m) = tb.poll_transmit() {
            cl.handle_message(Duration::ZERO, 1, &m);
            moved = true;
        }
        if !moved {
            break;
        }
    }
}

#[test]
fn list_read_set_and_refused_set() {
    let mut tb = table();
    let mut cl = ParamClient::default();
    cl.list(Duration::ZERO, (1, 1)).expect("started");
    pump(&mut cl, &mut tb);
    let Some(ParamEvent::ListComplete { params }) = cl.poll_event() else {
        panic!("no list")
    };
    assert_eq!(
        params.iter().map(|p| p.name.as_str()).collect::<Vec<_>>(),
        ["HDG_KP", "HDG_KD", "FLARE_ALT_M"]
    );

    cl.set(Duration::ZERO, (1, 1), "HDG_KP", 1.5)
        .expect("started");
    pump(&mut cl, &mut tb);
    assert_eq!(
        cl.poll_event(),
        Some(ParamEvent::SetDone {
            name: "HDG_KP".into(),
            requested: 1.5,
            actual: 1.5,
            accepted: true
        })
    );
    assert_eq!(
        tb.poll_change(),
        Some(ParamChange {
            name: "HDG_KP".into(),
            old: 0.8,
            new: 1.5
        })
    );

    // Out of range: the unchanged value comes back, with a STATUSTEXT saying why.
    cl.set(Duration::ZERO, (1, 1), "HDG_KP", 99.0)
        .expect("started");
    let m = cl.poll_transmit().expect("PARAM_SET");
    tb.handle_message(&m);
    while let Some(m) = tb.poll_transmit() {
        cl.handle_message(Duration::ZERO, 1, &m);
    }
    let (_, text) = tb.poll_text().expect("a text saying why");
    assert!(
        text.contains("HDG_KP") && text.contains("outside"),
        "{text}"
    );
    assert_eq!(
        cl.poll_event(),
        Some(ParamEvent::SetDone {
            name: "HDG_KP".into(),
            requested: 99.0,
            actual: 1.5,
            accepted: false
        })
    );
    assert_eq!(tb.poll_change(), None);
    assert_eq!(tb.stats().sets_refused, 1);

    cl.read(Duration::ZERO, (1, 1), "FLARE_ALT_M")
        .expect("started");
    pump(&mut cl, &mut tb);
    assert!(
        matches!(cl.poll_event(), Some(ParamEvent::ReadDone { param }) if param.value == 8.0 && param.index == 2)
    );
}

/// Regression: a value within its range but refused by the application used to be
/// echoed first (the client reported it accepted) and put back afterwards.
#[test]
fn a_set_the_validator_refuses_is_answered_only_with_the_value_in_force() {
    let mut tb = table();
    let mut cl = ParamClient::default();
    // The application's rule: the D gain at most a quarter of the P gain.
    let kp = tb.get("HDG_KP").expect("KP");
    let mut validator = |name: &str, value: f32| {
        if name == "HDG_KD" && value > kp / 4.0 {
            Err(format!("HDG_KD must not exceed HDG_KP/4 = {}", kp / 4.0))
        } else {
            Ok(())
        }
    };
    cl.set(Duration::ZERO, (1, 1), "HDG_KD", 1.0)
        .expect("started");
    let m = cl.poll_transmit().expect("PARAM_SET");
    assert!(tb.handle_message_with(&m, &mut validator));
    let mut values = Vec::new();
    while let Some(m) = tb.poll_transmit() {
        if let MavMessage::PARAM_VALUE(v) = &m {
            values.push(v.param_value);
        }
        cl.handle_message(Duration::ZERO, 1, &m);
    }
    assert_eq!(values, [0.1], "only the value in force goes out");
    assert_eq!(
        cl.poll_event(),
        Some(ParamEvent::SetDone {
            name: "HDG_KD".into(),
            requested: 1.0,
            actual: 0.1,
            accepted: false
        })
    );
    assert_eq!(cl.poll_event(), None);
    assert_eq!(tb.get("HDG_KD"), Some(0.1));
    assert_eq!(tb.poll_change(), None);
    let refusal = tb.poll_refusal().expect("the application hears of it");
    assert_eq!((refusal.value, refusal.in_force), (1.0, 0.1));
    assert!(refusal.reason.contains("HDG_KP/4"), "{refusal:?}");
    let (_, text) = tb.poll_text().expect("the station hears why");
    assert!(
        text.contains("HDG_KD") && text.contains("HDG_KP/4"),
        "{text}"
    );
    assert_eq!(tb.stats().sets_refused, 1);

    // Within the rule: taken and echoed once.
    cl.set(Duration::ZERO, (1, 1), "HDG_KD", 0.15)
        .expect("started");
    let m = cl.poll_transmit().expect("PARAM_SET");
    tb.handle_message_with(&m, &mut validator);
    while let Some(m) = tb.poll_transmit() {
        cl.handle_message(Duration::ZERO, 1, &m);
    }
    assert!(matches!(
        cl.poll_event(),
        Some(ParamEvent::SetDone { accepted: true, .. })
    ));
    assert_eq!(tb.get("HDG_KD"), Some(0.15));
}
