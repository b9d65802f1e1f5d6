"""train_segnet.py in parts: the fields and simulated camera it trains on (fields), the backend's
path from camera image to logits (network_path), the training samples and their augmentation
(samples), validation (validation), the networks (models), the export (export), a run's start
(start), what the C library does with freed memory (host_memory) and the training loop (loop).
"""
