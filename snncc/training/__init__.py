"""Training of the paper's models: presets, loss, split, trainer and quantization-aware fine-tuning."""
