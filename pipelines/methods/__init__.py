"""Render methods (notes -> actions -> audio), each one module, listed in a registry."""
