"""The Gait-Net data set: the collection protocol (paper Sec. IV-A-1), its schema, the
folder format, and ``collect`` / ``dataset check``."""

from gaitnet_mpc.dataset.protocol import CollectProtocol, PushProtocol, SetSpec
from gaitnet_mpc.dataset.schema import FEATURE_NAMES, SCHEMA_VERSION
from gaitnet_mpc.dataset.store import DatasetError

__all__ = [
    "FEATURE_NAMES",
    "SCHEMA_VERSION",
    "CollectProtocol",
    "DatasetError",
    "PushProtocol",
    "SetSpec",
]
