"""Distributions over physics sub-vectors: pytrees with sample, log_prob, kl, entropy."""
