"""Studies: many flights or many evaluations, and what they add up to. ACAI scans over grids and
sample sets (:mod:`~rotorfault.studies.scan`), the spin-assignment design search
(:mod:`~rotorfault.studies.design`), a vehicle's controllability certificate
(:mod:`~rotorfault.studies.certify`) and whether it agrees with flights
(:mod:`~rotorfault.studies.agreement`), the ``rotorfault simulate`` scenario file
(:mod:`~rotorfault.studies.scenario_file`), and one Monte Carlo engine split by job: the spec
(:mod:`~rotorfault.studies.campaign`), sampling (:mod:`~rotorfault.studies.sampling`), execution
backends (:mod:`~rotorfault.studies.backends`: threads or Dask), storage
(:mod:`~rotorfault.studies.storage`: the one Parquet writer, resumable), the engine that joins them
(:mod:`~rotorfault.studies.engine`), recorded batches streamed to Parquet
(:mod:`~rotorfault.studies.recording`), summaries (:mod:`~rotorfault.studies.summaries`) and robust
tuning (:mod:`~rotorfault.studies.tuning`, judged for holding through faults by
:mod:`~rotorfault.studies.hold`). The papers' Monte Carlo studies run on the same
engine (Lanzon's robustness study: :mod:`~rotorfault.studies.lanzon_robustness`).

May import: ``control``, ``flight``, ``allocation``, ``analysis``, ``plotting`` (on first use),
``rotorfault._typing`` and ``rotorfault._util``; never ``papers`` or ``cli``.
"""

from .agreement import CertifyAgreement, certify_against_flights
from .campaign import Campaign, CampaignResult, read_campaign, run_campaign
from .certify import Certificate, CertificateCase, certify
from .design import Design, DesignSearch, design_search
from .scan import EfficiencyScan, Scan, acai_scan, efficiency_scan, failure_samples, plot_efficiency_scan, read_scan
from .scenario_file import Scenario, load_scenario
from .recording import record_batch
from .hold import FaultCase, HoldCriteria, fault_set
from .tuning import HoldTuningResult, TuningResult, tune, tune_hold, tuning_campaign

__all__ = [
    "Campaign",
    "CampaignResult",
    "Certificate",
    "CertificateCase",
    "CertifyAgreement",
    "Design",
    "DesignSearch",
    "EfficiencyScan",
    "FaultCase",
    "HoldCriteria",
    "HoldTuningResult",
    "Scan",
    "Scenario",
    "TuningResult",
    "acai_scan",
    "certify",
    "certify_against_flights",
    "design_search",
    "efficiency_scan",
    "failure_samples",
    "fault_set",
    "load_scenario",
    "plot_efficiency_scan",
    "read_campaign",
    "record_batch",
    "read_scan",
    "run_campaign",
    "tune",
    "tune_hold",
    "tuning_campaign",
]
