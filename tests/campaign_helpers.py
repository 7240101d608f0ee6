"""Shared by the campaign tests: the small worlds and tours their campaigns draw from."""

from __future__ import annotations

__all__ = ["SMALL"]

#: CampaignParams fields for quick campaigns: small worlds of three kinds, short tours.
SMALL = {
    "kinds": ("rooms", "corridors", "open"),
    "world_size_min_m": 12.0,
    "world_size_max_m": 16.0,
    "tour_length_min_m": 12.0,
    "tour_length_max_m": 18.0,
}
