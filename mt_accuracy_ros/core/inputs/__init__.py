"""What the core takes from outside, checked before anything trusts it.

* :mod:`.safe_files` - machine and model description files: regular files of
  bounded size, read non-blocking; errors that never quote a file's content.
* :mod:`.stream_history` - the sample index and stamp of a batch of a sampled
  stream, plausible against the stream's own history (forged or corrupt
  batches are refused and leave the history alone).
"""
