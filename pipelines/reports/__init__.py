"""Comparison of methods: figures, the HTML report and bowing plots."""
