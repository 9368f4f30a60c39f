"""The schedule tables of an env core's rows: one slot per distinct scenario in use, shared by
the rows that run it (a batch of rows on one scenario packs it once), counted so that a
slot no row uses any more is freed; the tables grow (doubling their slots, up to one per
row, or their breakpoints) when a new scenario does not fit.
"""

from __future__ import annotations

from steamtemp_gym import scenarios as sc
from steamtemp_gym.envs.state import EnvState, with_tables


class ScheduleSlots:
    """Which slot of the schedule tables each scenario in use holds and how many rows use
    it; ``n_slots``: the tables' slots at the start, all free."""

    def __init__(self, n_slots: int) -> None:
        self.used: dict[sc.Scenario, list[int]] = {}  # scenario -> [slot, rows using it]
        self.free: list[int] = list(range(n_slots))

    def assign(
        self, state: EnvState, b: int, prev: sc.Scenario | None, scenario: sc.Scenario
    ) -> EnvState:
        """``state`` with row b pointed at the slot of ``scenario`` (packed there if no row
        uses it yet) instead of ``prev``'s: the same state, or one with larger tables."""
        if prev is not None:
            entry = self.used[prev]
            entry[1] -= 1
            if entry[1] == 0:
                del self.used[prev]
                self.free.append(entry[0])
        entry = self.used.get(scenario)
        if entry is None:
            need = sc.max_breakpoints([scenario])
            n_slots, k = state.bp_t.shape[0], state.bp_t.shape[2]
            if not self.free or need > k:
                grow = n_slots if self.free else min(2 * n_slots, state.slot.shape[0])
                grow = max(grow, n_slots)
                self.free += list(range(n_slots, grow))
                state = with_tables(state, grow, max(need, k))
            entry = self.used[scenario] = [min(self.free), 0]
            self.free.remove(entry[0])
            sc.pack(scenario, state.bp_t[entry[0]], state.bp_v[entry[0]], state.bp_n[entry[0]])
        entry[1] += 1
        state.slot[b] = entry[0]
        return state
