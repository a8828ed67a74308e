//! The deployment files agree with the code: every environment variable is a real
//! setting, probes and scrape paths are real routes, the port is the one served, the
//! presets file parses, and the image puts the model and runtime where it says.

#![allow(clippy::unwrap_used)] // test code: a failure should panic

use std::collections::BTreeMap;
use std::path::Path;

use ariadne_dlo::cli::ServeArgs;
use ariadne_dlo::detect::DetectorConfig;
use ariadne_dlo::http::{Presets, ServeConfig};
use clap::{CommandFactory, Parser};
use serde::Deserialize;
use serde_yaml::Value;

#[derive(Parser)]
struct Wrapper {
    #[command(flatten)]
    args: ServeArgs,
}

/// Every document of every manifest the kustomization lists, by kind.
fn manifests() -> BTreeMap<String, Vec<Value>> {
    let dir = Path::new("k8s");
    let kustomization: Value =
        serde_yaml::from_str(&std::fs::read_to_string(dir.join("kustomization.yaml")).unwrap())
            .unwrap();
    let mut by_kind: BTreeMap<String, Vec<Value>> = BTreeMap::new();
    for file in kustomization["resources"].as_sequence().unwrap() {
        let text = std::fs::read_to_string(dir.join(file.as_str().unwrap())).unwrap();
        for doc in serde_yaml::Deserializer::from_str(&text) {
            let v = Value::deserialize(doc).unwrap();
            by_kind
                .entry(v["kind"].as_str().unwrap().to_string())
                .or_default()
                .push(v);
        }
    }
    by_kind
}

fn one<'a>(m: &'a BTreeMap<String, Vec<Value>>, kind: &str) -> &'a Value {
    let docs = &m[kind];
    assert_eq!(docs.len(), 1, "one {kind}");
    &docs[0]
}

fn config_map<'a>(m: &'a BTreeMap<String, Vec<Value>>, name: &str) -> &'a Value {
    m["ConfigMap"]
        .iter()
        .find(|c| c["metadata"]["name"] == name)
        .unwrap_or_else(|| panic!("ConfigMap {name}"))
}

/// Environment variables the service reads: the env twins of its flags.
fn known_env() -> Vec<String> {
    Wrapper::command()
        .get_arguments()
        .filter_map(|a| a.get_env().map(|e| e.to_string_lossy().into_owned()))
        .collect()
}

fn default_port() -> u16 {
    ServeConfig::default().bind.port()
}

fn route_paths() -> Vec<String> {
    let doc = ariadne_dlo::http::openapi();
    doc.paths.paths.keys().cloned().collect()
}

#[test]
fn manifests_match_the_code() {
    let m = manifests();
    let deployment = one(&m, "Deployment");
    let pod = &deployment["spec"]["template"];
    let container = &pod["spec"]["containers"][0];
    let known = known_env();

    // Port: the container port, the bind address and the scrape annotation.
    let port = default_port();
    assert_eq!(
        container["ports"][0]["containerPort"].as_u64(),
        Some(port as u64)
    );
    assert_eq!(
        pod["metadata"]["annotations"]["prometheus.io/port"].as_str(),
        Some(port.to_string().as_str())
    );

    // Environment: every variable set is one the service reads.
    let settings = config_map(&m, "ariadne-settings");
    let mut env: BTreeMap<String, String> = BTreeMap::new();
    for (k, v) in settings["data"].as_mapping().unwrap() {
        env.insert(k.as_str().unwrap().into(), v.as_str().unwrap().into());
    }
    for e in container["env"].as_sequence().unwrap() {
        env.insert(
            e["name"].as_str().unwrap().into(),
            e["value"].as_str().unwrap_or("").into(),
        );
    }
    for name in env.keys() {
        assert!(
            known.contains(name),
            "{name} is set in k8s/ but no flag reads it"
        );
    }
    let bind = &env["ARIADNE_BIND"];
    assert!(bind.ends_with(&format!(":{port}")), "ARIADNE_BIND {bind}");
    let settings_ref = &container["envFrom"][0]["configMapRef"]["name"];
    assert_eq!(settings_ref, &settings["metadata"]["name"]);

    // The settings parse as the service would parse them.
    let mut argv = vec!["test".to_string()];
    let command = Wrapper::command();
    for (k, v) in env.iter().filter(|(_, v)| !v.is_empty()) {
        let arg = command
            .get_arguments()
            .find(|a| a.get_env().is_some_and(|e| e == k.as_str()))
            .unwrap();
        argv.push(format!("--{}", arg.get_long().unwrap()));
        argv.push(v.clone());
    }
    let parsed = Wrapper::try_parse_from(&argv)
        .unwrap_or_else(|e| panic!("{argv:?}: {e}"))
        .args;

    // Probes and scrape path are routes the service has.
    let routes = route_paths();
    for probe in ["startupProbe", "readinessProbe", "livenessProbe"] {
        let path = container[probe]["httpGet"]["path"].as_str().unwrap();
        assert!(
            routes.iter().any(|r| r == path),
            "{probe} {path} is not a route"
        );
    }
    assert_eq!(container["readinessProbe"]["httpGet"]["path"], "/readyz");
    assert_eq!(container["livenessProbe"]["httpGet"]["path"], "/healthz");
    let scrape = pod["metadata"]["annotations"]["prometheus.io/path"]
        .as_str()
        .unwrap();
    assert!(routes.iter().any(|r| r == scrape), "scrape path {scrape}");

    // The presets file: mounted where ARIADNE_PRESETS points, and loadable.
    let presets_path = Path::new(&env["ARIADNE_PRESETS"]);
    let mount = container["volumeMounts"]
        .as_sequence()
        .unwrap()
        .iter()
        .find(|v| presets_path.starts_with(v["mountPath"].as_str().unwrap()))
        .expect("a volume mounted at the presets file's folder");
    let volume = pod["spec"]["volumes"]
        .as_sequence()
        .unwrap()
        .iter()
        .find(|v| v["name"] == mount["name"])
        .unwrap();
    let presets_map = config_map(&m, volume["configMap"]["name"].as_str().unwrap());
    let file_name = presets_path.file_name().unwrap().to_str().unwrap();
    let text = presets_map["data"][file_name]
        .as_str()
        .expect("the presets file's key");
    let tmp = std::env::temp_dir().join(format!("ariadne-presets-{}.json", std::process::id()));
    std::fs::write(&tmp, text).unwrap();
    let presets = Presets::load(Some(&tmp)).unwrap();
    std::fs::remove_file(&tmp).unwrap();
    assert!(
        presets.names().len() > 2,
        "cells' presets beside the built-in ones"
    );

    // Shutdown: Kubernetes waits at least preStop + not-ready delay + the deadline of
    // the last request admitted + the drain grace, all in a row.
    let pre_stop = container["lifecycle"]["preStop"]["sleep"]["seconds"]
        .as_u64()
        .unwrap();
    let grace = pod["spec"]["terminationGracePeriodSeconds"]
        .as_u64()
        .unwrap();
    let needed = pre_stop
        + parsed.shutdown_delay_s
        + parsed.deadline_ms.div_ceil(1000)
        + parsed.shutdown_grace_s;
    assert!(
        grace >= needed,
        "terminationGracePeriodSeconds {grace} < {needed}"
    );

    // Memory: the upload budget, plus per worker the largest decoded photo (RGB) and its
    // mask, plus 128 MiB for the process and the model, fit the limit.
    let limit = container["resources"]["limits"]["memory"].as_str().unwrap();
    let limit_bytes: u64 = limit.strip_suffix("Gi").unwrap().parse::<u64>().unwrap() << 30;
    let workers = container["env"]
        .as_sequence()
        .unwrap()
        .iter()
        .any(|e| e["name"] == "ARIADNE_WORKERS");
    assert!(workers, "the worker count comes from the CPU limit");
    let cpus: u64 = container["resources"]["limits"]["cpu"]
        .as_str()
        .unwrap()
        .parse()
        .unwrap();
    let needed = parsed.upload_budget_bytes as u64 + cpus * parsed.max_pixels * 4 + (128 << 20);
    assert!(
        needed <= limit_bytes,
        "memory limit {limit} < {needed} bytes needed"
    );

    // Requests equal limits; security context as required.
    assert_eq!(
        container["resources"]["requests"],
        container["resources"]["limits"]
    );
    assert_eq!(pod["spec"]["securityContext"]["runAsNonRoot"], true);
    assert_eq!(container["securityContext"]["readOnlyRootFilesystem"], true);
    assert_eq!(
        deployment["spec"]["strategy"]["rollingUpdate"]["maxUnavailable"],
        0
    );
    assert!(deployment["spec"]["replicas"].as_u64().unwrap() >= 2);

    // Everything selects the same pods and targets the same Deployment.
    let labels = &pod["metadata"]["labels"];
    let name = &deployment["metadata"]["name"];
    for (kind, selector) in [
        ("Service", &one(&m, "Service")["spec"]["selector"]),
        (
            "PodDisruptionBudget",
            &one(&m, "PodDisruptionBudget")["spec"]["selector"]["matchLabels"],
        ),
        ("Deployment", &deployment["spec"]["selector"]["matchLabels"]),
    ] {
        for (k, v) in selector.as_mapping().unwrap() {
            assert_eq!(&labels[k], v, "{kind} selects {k:?}");
        }
    }
    assert_eq!(
        &one(&m, "HorizontalPodAutoscaler")["spec"]["scaleTargetRef"]["name"],
        name
    );
    assert_eq!(
        one(&m, "Service")["spec"]["ports"][0]["targetPort"],
        container["ports"][0]["name"]
    );
}

#[test]
fn dockerfile_matches_the_code() {
    let text = std::fs::read_to_string("docker/Dockerfile").unwrap();
    let port = default_port();
    assert!(text.contains(&format!("EXPOSE {port}")));
    assert!(text.contains(&format!("ARIADNE_BIND=0.0.0.0:{port}")));
    assert!(text.contains(r#"ENTRYPOINT ["/usr/local/bin/ariadne", "serve"]"#));
    // Every ENV name is a setting, and the files it names are copied there.
    let known = known_env();
    for line in text.lines().skip_while(|l| !l.starts_with("ENV ")) {
        let Some((name, value)) = line
            .trim_start_matches("ENV ")
            .trim()
            .trim_end_matches('\\')
            .trim()
            .split_once('=')
        else {
            break;
        };
        assert!(
            known.contains(&name.to_string()),
            "Dockerfile sets {name}, which no flag reads"
        );
        if value.starts_with('/') && name != "ARIADNE_BIND" {
            assert!(
                text.lines()
                    .any(|l| l.starts_with("COPY") && l.trim_end().ends_with(value)),
                "{name}={value} is not a COPY destination"
            );
        }
    }
    let model = DetectorConfig::default().model;
    assert!(
        text.contains(&format!("COPY {} ", model.display())),
        "the bundled model is copied"
    );
}
