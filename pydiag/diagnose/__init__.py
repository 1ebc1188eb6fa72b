"""Stage 8: diagnosis: a record's fit classified (failure mode and severity, each fault
group tested held out), and a machine's every stage fitted and judged against its healthy
baselines."""
