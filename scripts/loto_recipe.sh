# shellcheck shell=bash
# The leave-one-tile-out networks' training recipes: the train_segnet arguments that
# scripts/loto.sh (train, recipe-cpu, eval) and benchmarks/train_cpu.sh share, in one place.
# Sourced; LOTO_ARCH (environment) picks the network:
#   mobilenetv2 (default)  the deployment MobileNetV2's (examples/models/mobilenetv2-dubai-all/README.md):
#                          ImageNet encoder weights from .device/mnv2_enc.pt (bash scripts/loto.sh
#                          weights), 1784 steps of 32 crops of 300 px
#   erfnet                 the bundled ERFNet's first learning-rate cycle (its README's "The run":
#                          examples/models/erfnet-dubai/README.md): full width, from scratch, at most
#                          1563 steps of 32 crops of 352 px; cycle 2 gained nothing on its validation tile
# Sets
#   loto_arch    the network (train_segnet --arch)
#   loto_recipe  the network, its initialisation, optimiser and augmentation
#   loto_batch   batch, crop and warm-up of the full-size recipe
#   loto_steps   the full-size recipe's steps (a device call's cap, LOTO_STEP_CAP overrides it)
# Each caller adds its device, sampler, threads, fields, seed and schedule.
# shellcheck disable=SC2034  # used by the scripts that source this file
loto_arch=${LOTO_ARCH:-mobilenetv2}
case "$loto_arch" in
mobilenetv2)
  loto_recipe=(--arch mobilenetv2 --encoder-weights .device/mnv2_enc.pt --frozen-blocks 4 --no-image-pooling
               --lr 1e-3 --weight-decay 0.01 --ema 0.998 --augment altitude)
  loto_batch=(--batch 32 --crop 300 --warmup 100)
  loto_steps=1784
  ;;
erfnet)
  loto_recipe=(--arch erfnet --width 1.0 --lr 2e-3 --weight-decay 1e-4 --ema 0.999 --augment altitude)
  loto_batch=(--batch 32 --crop 352 --warmup 200)
  loto_steps=1563
  ;;
*)
  echo "LOTO_ARCH=$loto_arch: mobilenetv2 or erfnet" >&2
  exit 2
  ;;
esac
