"""How a run is cut into work units: chunks of points and rounds of chunks (:mod:`.rounds`).

Light on purpose (no engine import), so that the command line's ``--help`` shows the
defaults without loading the engine.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Decomposition", "CHUNK_POINTS", "ROUND_CHUNKS", "ANSWER_WEIGHT"]

#: Query points of a chunk (default of ``--chunk-size``).
CHUNK_POINTS = 2048
#: Most chunks in one round (default of ``--round-chunks``).
ROUND_CHUNKS = 16
#: Weight of an answer task against a solve task in the progress display's share.
ANSWER_WEIGHT = 0.1


@dataclass(frozen=True)
class Decomposition:
    """How a run's points are cut: ``chunk`` points a chunk, rounds of 1, 2, 4, … and at
    most ``most`` chunks.  The results depend on these two numbers (and the seed), never
    on where the tasks run."""

    chunk: int = CHUNK_POINTS
    most: int = ROUND_CHUNKS

    def __post_init__(self):
        if int(self.chunk) < 1 or int(self.most) < 1:
            raise ValueError("chunk size and chunks per round must be positive")

    def chunks(self, n: int) -> list[slice]:
        """The chunks of ``n`` points, in order."""
        return [slice(lo, min(lo + self.chunk, n)) for lo in range(0, n, self.chunk)]

    def rounds(self, chunks: int) -> list[list[int]]:
        """The chunk indices of each round: 1, 2, 4, … chunks, at most ``most``."""
        out, lo, size = [], 0, 1
        while lo < chunks:
            take = min(size, self.most, chunks - lo)
            out.append(list(range(lo, lo + take)))
            lo += take
            size *= 2
        return out


