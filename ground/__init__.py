"""The ground floor every package stands on, split by concept (docs/architecture.md): :mod:`ground.data` the
dataset model, :mod:`ground.image` image files and pixels, :mod:`ground.detect` detector outputs and COCO
evaluation, :mod:`ground.run` where work runs, :mod:`ground.config` typed configs, :mod:`ground.cli` what every
command line shares. Nothing here imports curate, synth, train, eval or fuzzyfire."""
