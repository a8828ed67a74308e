#!/usr/bin/env bash
# Photographs for train_field.py's --photo-textures, taken offline from three PyPI
# wheels that ship them (nothing else is downloaded):
#   scikit-image: astronaut, rocket (a launch pad)
#   scikit-learn: china (a temple), flower
#   matplotlib:   grace_hopper (a portrait)
# None of them is one of the photographs scripts/stress.py draws its `photo` kind on.
# The wheels' versions are pinned and the photographs' checksums verified, so that a
# run with --photo-textures makes the scenes of the networks the model card measured
# (models/README.md, "Photographs among the backgrounds"; not the bundled recipe).
# Usage: training/fetch_background_photos.sh [OUT_DIR]   (default out/background-photos)
set -euo pipefail
out=${1:-out/background-photos}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python3 -m pip download --quiet --no-deps --only-binary=:all: --python-version 3.11 \
    --platform manylinux2014_x86_64 --platform manylinux_2_28_x86_64 \
    scikit-image==0.26.0 scikit-learn==1.9.1 matplotlib==3.11.2 -d "$work"
mkdir -p "$out"
# Each photograph, by its path inside its wheel (zipfile: no unzip needed).
python3 - "$work" "$out" <<'PY'
import sys, zipfile
from pathlib import Path
work, out = Path(sys.argv[1]), Path(sys.argv[2])
wanted = {
    "scikit_image": ["skimage/data/astronaut.png", "skimage/data/rocket.jpg"],
    "scikit_learn": ["sklearn/datasets/images/china.jpg", "sklearn/datasets/images/flower.jpg"],
    "matplotlib": ["matplotlib/mpl-data/sample_data/grace_hopper.jpg"],
}
for prefix, members in wanted.items():
    (wheel,) = work.glob(f"{prefix}-*.whl")
    with zipfile.ZipFile(wheel) as z:
        for m in members:
            (out / Path(m).name).write_bytes(z.read(m))
PY
(cd "$out" && sha256sum --check --quiet) <<'SUMS'
88431cd9653ccd539741b555fb0a46b61558b301d4110412b5bc28b5e3ea6cb5  astronaut.png
8378025ad2519d649d02e32bd98990db4ab572357d9f09841c2fbfbb4fefad29  china.jpg
a77f6ec41e353afdf8bdff2ea981b2955535d8d83294f8cfa49cf4e423dd5638  flower.jpg
a8ca6d734765703b09728ab47fe59f473d93ae3967fc24c7c0288c3c7adb7130  grace_hopper.jpg
c2dd0de7c538df8d111e479619b129464d0269d0ae5fd18ca91d33a7fdfea95c  rocket.jpg
SUMS
ls "$out"
