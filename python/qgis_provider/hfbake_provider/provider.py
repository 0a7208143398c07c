"""The provider: one algorithm per product."""

from qgis.core import QgsProcessingProvider

from .algorithms import ALGORITHMS


class HfbakeProvider(QgsProcessingProvider):
    def id(self):
        return "hfbake"

    def name(self):
        return "hfbake"

    def longName(self):  # noqa: N802
        return "hfbake: terrain visibility and ambient occlusion"

    def loadAlgorithms(self):  # noqa: N802
        for algorithm in ALGORITHMS:
            self.addAlgorithm(algorithm())
