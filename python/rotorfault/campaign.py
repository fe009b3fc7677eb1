"""Deprecated name of :mod:`rotorfault.studies` (split in issue 26 into the campaign spec,
sampling, backends, storage, summaries and tuning; this name works for one release and warns).
Import from :mod:`rotorfault.studies` (``Campaign``, ``run_campaign``, ``tune``, ...)."""

from ._util.deprecation import warn

warn("module rotorfault.campaign", "rotorfault.studies (campaign, sampling, summaries, tuning)", stacklevel=2)

from .studies.campaign import *  # noqa: E402,F401,F403
from .studies.campaign import _CampaignTask, _pair, _relative  # noqa: E402,F401
from .studies.sampling import *  # noqa: E402,F401,F403
from .studies.summaries import *  # noqa: E402,F401,F403
from .studies.tuning import *  # noqa: E402,F401,F403
from .studies.tuning import _objective, _score  # noqa: E402,F401
