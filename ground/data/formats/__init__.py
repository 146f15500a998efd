"""Dataset formats: readers return ``ReadResult`` (dataset + problems), writers write self-describing folders."""
