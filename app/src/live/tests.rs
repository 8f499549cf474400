//! The server over a memory backend, with tokio-modbus as the client (same process);
//! what a monitor or gateway run loads (the diagnosers and their constraint rewrite).

use super::backend::MemoryBackend;
use super::runtime::{CycleStats, serve_backend};
use std::net::SocketAddr;
use std::path::Path;
use tokio_modbus::client::{Reader as _, Writer as _};
use tokio_modbus::prelude::SlaveContext as _;
use tokio_modbus::{ExceptionCode, Slave};
use vigie_core::live::config::GatewayConfig;
use vigie_core::live::iomap::IoMap;
use vigie_core::plant::Plant;

fn station() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../layouts/sorting-station")
}

#[test]
fn memory_backend_served_round_trip_and_exceptions() {
    let plant = Plant::load(&station().join("plant.ron")).unwrap();
    let (map, _) = IoMap::load(&station().join("io-map.ron"), &plant).unwrap();
    let text = format!(
        "Gateway(mode: Emulator, plant: {:?}, cycle_ms: 5, server: Modbus(bind: \"127.0.0.1:0\", plc: \"127.0.0.1\"))",
        station().display().to_string()
    );
    let config = GatewayConfig::from_ron(&text, Path::new("t.ron")).unwrap();
    let server_config = config.server.clone().unwrap();
    let backend = MemoryBackend {
        inputs: {
            let mut b = vigie_core::Bits::zeros(plant.inputs.len());
            b.set(3, true);
            b.set(7, true);
            b
        },
        outputs: vigie_core::Bits::zeros(plant.outputs.len()),
    };
    let plant_for_server = plant.clone();
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    rt.block_on(async {
        let (addr_tx, addr_rx) = tokio::sync::oneshot::channel::<SocketAddr>();
        let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
        let mut addr_tx = Some(addr_tx);
        let served = async move {
            let mut emit = move |e: serde_json::Value| {
                if let Some(a) = e["address"].as_str().and_then(|a| a.parse().ok())
                    && let Some(tx) = addr_tx.take()
                {
                    let _ = tx.send(a);
                }
            };
            let mut stats = CycleStats::default();
            let map = vigie_core::live::LinkMap::Modbus(map);
            let plant = plant_for_server;
            let pki = std::env::temp_dir().join("vigie-unit-pki");
            let serve = super::link::Serve {
                config: &config,
                server: &server_config,
                map: Some(&map),
                plant: &plant,
                pki: &pki,
            };
            serve_backend(
                &serve,
                backend,
                async {
                    let _ = stop_rx.await;
                },
                &mut emit,
                &mut stats,
            )
            .await
            .unwrap();
        };
        let client = async move {
            let addr = addr_rx.await.unwrap();
            let mut ctx = tokio_modbus::client::tcp::connect_slave(addr, Slave(1))
                .await
                .unwrap();
            let di = ctx.read_discrete_inputs(0, 11).await.unwrap().unwrap();
            assert!(di[3] && di[7] && !di[0]);
            ctx.write_multiple_coils(2, &[true, false, true])
                .await
                .unwrap()
                .unwrap();
            assert_eq!(
                ctx.read_coils(0, 7).await.unwrap().unwrap(),
                vec![false, false, true, false, true, false, false]
            );
            assert_eq!(
                ctx.read_discrete_inputs(plant.inputs.len() as u16 - 1, 2)
                    .await
                    .unwrap(),
                Err(ExceptionCode::IllegalDataAddress)
            );
            assert_eq!(
                ctx.read_coils(0, 0).await.unwrap(),
                Err(ExceptionCode::IllegalDataValue)
            );
            assert_eq!(
                ctx.write_single_register(0, 1).await.unwrap(),
                Err(ExceptionCode::IllegalDataAddress)
            );
            ctx.set_slave(Slave(9));
            assert_eq!(
                ctx.read_coils(0, 1).await.unwrap(),
                Err(ExceptionCode::GatewayTargetDevice)
            );
            let _ = stop_tx.send(());
        };
        tokio::join!(served, client);
    });
}

#[test]
fn the_run_loads_the_diagnosers_unless_switched_off() {
    use vigie_core::symbols::Space;
    // The committed configurations: the diagnosers on by default.
    for name in ["gateway-monitor.ron", "gateway-enforce.ron"] {
        let setup = super::runtime::load(&station().join(name)).unwrap();
        assert!(setup.config.diagnosers, "{name}");
        let compiled = setup.diagnosers.as_ref().expect("diagnosers loaded");
        assert!(compiled.components.iter().any(|c| c.id == "table"));
        // The bundle is the cooperation's: flags and estimates declared, constraints
        // rewritten (one DSTOP_ per stop partition).
        assert!(matches!(
            setup.bundle.symbols.lookup("def_C4"),
            Some((Space::Aux, _))
        ));
        assert!(
            setup
                .bundle
                .constraints
                .constraints
                .iter()
                .any(|c| c.id == "DSTOP_P")
        );
    }
    // Switched off: the plant's constraints as written.
    let text = format!(
        "Gateway(mode: Monitor, plant: {:?}, client: Modbus(address: \"127.0.0.1:1502\"), diagnosers: false)",
        station().display().to_string()
    );
    let config = GatewayConfig::from_ron(&text, Path::new("t.ron")).unwrap();
    assert!(!config.runs_diagnosers());
    let (bundle, diagnosers) = super::runtime::load_plant(&config).unwrap();
    assert!(diagnosers.is_none());
    assert!(bundle.symbols.lookup("def_C4").is_none());
    assert!(
        bundle
            .constraints
            .constraints
            .iter()
            .all(|c| !c.id.starts_with("DSTOP"))
    );
    // Emulator mode never runs them.
    let text = format!(
        "Gateway(mode: Emulator, plant: {:?}, server: Modbus(bind: \"127.0.0.1:0\"))",
        station().display().to_string()
    );
    let config = GatewayConfig::from_ron(&text, Path::new("t.ron")).unwrap();
    assert!(config.diagnosers && !config.runs_diagnosers());
}
