# shellcheck shell=bash
# The leave-one-tile-out networks' training recipes: the train_segnet arguments that
# scripts/loto.sh (train, recipe-cpu, eval) and benchmarks/train_cpu.sh share, in one place.
# Sourced; LOTO_ARCH (environment) picks the network:
#   mobilenetv2 (default)  the deployment MobileNetV2's (examples/models/mobilenetv2-dubai-all/README.md):
#                          ImageNet encoder weights from .device/mnv2_enc.pt (bash scripts/loto.sh
#                          weights), 1784 steps of 32 crops of 300 px
#   mobilenetv2-140        the same recipe on the width-1.4 MobileNetV2 with every block
#                          (train_segnet --encoder mnv2-140-b16, adaptseg_tools.mobilenet_v2_140):
#                          TF-Hub's ImageNet weights from .device/mnv2_140_enc.pt; about twice
#                          the CPU time a step (2-core VM, alone: 8.5 against 18 crops a second)
#   erfnet                 the bundled ERFNet's first learning-rate cycle (its README's "The run":
#                          examples/models/erfnet-dubai/README.md): full width, from scratch, at most
#                          1563 steps of 32 crops of 352 px; cycle 2 gained nothing on its validation tile
# Sets
#   loto_net      the recipe's name (LOTO_ARCH)
#   loto_arch     the network (train_segnet --arch)
#   loto_encoder  the ImageNet encoder weights it starts from ("" for none)
#   loto_recipe   the network, its initialisation, optimiser and augmentation
#   loto_batch    batch, crop and warm-up of the full-size recipe
#   loto_steps    the full-size recipe's steps (a device call's cap, LOTO_STEP_CAP overrides it)
# Each caller adds its device, sampler, threads, fields, seed and schedule.
# shellcheck disable=SC2034  # used by the scripts that source this file
loto_net=${LOTO_ARCH:-mobilenetv2}
mnv2_recipe=(--frozen-blocks 4 --no-image-pooling --lr 1e-3 --weight-decay 0.01 --ema 0.998 --augment altitude)
case "$loto_net" in
mobilenetv2)
  loto_arch=mobilenetv2
  loto_encoder=.device/mnv2_enc.pt
  loto_recipe=(--arch mobilenetv2 --encoder-weights "$loto_encoder" "${mnv2_recipe[@]}")
  loto_batch=(--batch 32 --crop 300 --warmup 100)
  loto_steps=1784
  ;;
mobilenetv2-140)
  loto_arch=mobilenetv2
  loto_encoder=.device/mnv2_140_enc.pt
  loto_recipe=(--arch mobilenetv2 --encoder mnv2-140-b16 --encoder-weights "$loto_encoder" "${mnv2_recipe[@]}")
  loto_batch=(--batch 32 --crop 300 --warmup 100)
  loto_steps=1784
  ;;
erfnet)
  loto_arch=erfnet
  loto_encoder=""
  loto_recipe=(--arch erfnet --width 1.0 --lr 2e-3 --weight-decay 1e-4 --ema 0.999 --augment altitude)
  loto_batch=(--batch 32 --crop 352 --warmup 200)
  loto_steps=1563
  ;;
*)
  echo "LOTO_ARCH=$loto_net: mobilenetv2, mobilenetv2-140 or erfnet" >&2
  exit 2
  ;;
esac
