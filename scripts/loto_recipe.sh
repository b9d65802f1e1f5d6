# shellcheck shell=bash
# The deployment MobileNetV2's training recipe (examples/models/mobilenetv2-dubai-all/README.md):
# the train_segnet arguments that scripts/loto.sh (train, recipe-cpu) and benchmarks/train_cpu.sh
# share, in one place. Sourced; sets
#   loto_recipe  the network, its initialisation (ImageNet encoder weights from
#                .device/mnv2_enc.pt: bash scripts/loto.sh weights), optimiser and augmentation
#   loto_batch   batch, crop and warm-up of the full-size recipe (1784 steps of them)
# Each caller adds its device, sampler, threads, fields, seed and schedule.
# shellcheck disable=SC2034  # used by the scripts that source this file
loto_recipe=(--arch mobilenetv2 --encoder-weights .device/mnv2_enc.pt --frozen-blocks 4 --no-image-pooling
             --lr 1e-3 --weight-decay 0.01 --ema 0.998 --augment altitude)
# shellcheck disable=SC2034
loto_batch=(--batch 32 --crop 300 --warmup 100)
