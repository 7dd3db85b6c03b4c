"""Decoding every instance of a file at once (full ``parse``, ``export``).

For now this is the reference tokenizer applied instance by instance.
"""

from __future__ import annotations


def decode_all(step_file):
    """Yield every instance record of ``step_file`` in file order."""
    return step_file.careful_records()
