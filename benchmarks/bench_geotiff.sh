#!/usr/bin/env bash
# What a large GeoTIFF field costs: dubai-tile-6 resampled (nearest neighbour) to SIZE x SIZE
# pixels of 5 cm under UTM 40N (uncompressed GeoTIFFs, as orthomosaic tools write them by
# default), then loaded by gdal::load_field and its map written by gdal::write_map_geotiff.
#   bash benchmarks/bench_geotiff.sh BENCH_BINARY [SIZE (20000)] [WORK_DIR (a temporary one)]
set -euo pipefail
bin=$1 size=${2:-20000}
work=${3:-$(mktemp -d)}
tile="$(dirname "$0")/../examples/data/dubai-tile-6"
mkdir -p "$work/field"
side=$(awk -v n="$size" 'BEGIN { printf "%.2f", n * 0.05 }')
grid=(-a_srs EPSG:32640 -a_ullr 329000 "$(awk -v s="$side" 'BEGIN { printf "%.2f", 2787000 + s }')" \
      "$(awk -v s="$side" 'BEGIN { printf "%.2f", 329000 + s }')" 2787000)
gdal_translate -q -of GTiff -r near -outsize "$size" "$size" "${grid[@]}" "$tile/image.jpg" "$work/field/ortho.tif"
gdal_translate -q -of GTiff -r near -outsize "$size" "$size" "${grid[@]}" "$tile/labels.png" "$work/field/labels.tif"
sed -e '/^gsd_cm:/d' -e 's/^labels: .*/labels: labels.tif/' -e 's/^image: .*/image: ortho.tif/' \
  "$tile/field.yaml" >"$work/field/field.yaml"
echo "## GeoTIFF field of $size x $size px: ortho.tif $(du -m "$work/field/ortho.tif" | cut -f1) MB," \
     "labels.tif $(du -m "$work/field/labels.tif" | cut -f1) MB"
"$bin" "$work/field" "$work/out"
[ -n "${3:-}" ] || rm -rf "$work"
