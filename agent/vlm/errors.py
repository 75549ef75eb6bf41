"""The one error every VLM backend raises when it cannot answer.

A single type lets the behaviour tree report any backend's failure the same way; the text always
names the backend's server or model folder and what to change.
"""

from __future__ import annotations


class VLMError(RuntimeError):
    """A VLM backend could not produce probabilities; the text says where and why."""
