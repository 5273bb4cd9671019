"""Label-free deployment fine-tuning: adapt a lowered model to a target's integer arithmetic with the
float graph as teacher (distillation on unlabelled inputs). ``engine.finetune`` is the entry point;
a target provides its arithmetic as a ``protocol.DifferentiableArithmetic``."""
