"""Outer loops that learn the randomisation itself: UDR, LSDR/EPOpt, SimOpt, ES-MAML."""
