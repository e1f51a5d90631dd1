"""Shards: `--shard K/N` runs the K-th of N deterministic shares of a run's cases, so a job
array (Slurm, a CI matrix) spreads a bench over nodes; `harness merge` joins the shard
folders (harness/bench/merge.py). The share is round robin over the cases in the order the
sweep file declares them (each shard gets every size), so it is the same on every node."""

from dataclasses import dataclass

from harness import HarnessError


@dataclass(frozen=True)
class Shard:
    k: int  # 1-based
    n: int

    def __str__(self):
        return f"{self.k}/{self.n}"

    def share(self, items):
        """This shard's items: the (k-1)-th, then every n-th after it."""
        return list(items)[self.k - 1 :: self.n]

    @property
    def first(self):
        """Shard 1 (it keeps the paper sweep's figure state)."""
        return self.k == 1

    def takes(self, index):
        """Whether this shard runs the index-th (0-based) of a run's one-measurement studies:
        they go round robin too, study i to shard i mod N + 1, so no shard carries them all."""
        return index % self.n == self.k - 1


WHOLE = Shard(1, 1)


def parse(text):
    """'K/N' (1 ≤ K ≤ N) as a Shard; anything else refused in one line."""
    parts = str(text).split("/")
    try:
        k, n = (int(p, 10) for p in parts)
    except ValueError:
        raise HarnessError(f"--shard needs K/N with whole numbers, 1 <= K <= N (got '{text}')", code=2) from None
    if not 1 <= k <= n:
        raise HarnessError(f"--shard needs K/N with 1 <= K <= N (got '{text}')", code=2)
    return Shard(k, n)
