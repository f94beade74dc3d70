"""The double-loop sliding-mode controller: BTINTSMC position loop -> ABFSMC attitude loop."""

from nfmr_dlsmc.core.cascade import CascadeController
from nfmr_dlsmc.core.gains import DlsmcConfig
from nfmr_dlsmc.core.inner_loop import AbfsmcInnerLoop
from nfmr_dlsmc.core.outer_loop import BtintsmcOuterLoop

__all__ = ['DlsmcController', 'DlsmcLoops']


class DlsmcLoops:
    """
    What a controller of the BTINTSMC and ABFSMC loops takes from its ``DlsmcConfig``.

    The limits, the period, the omega low-pass (D14) and both loops' gains in use, for the
    paper's cascade (:class:`DlsmcController`) and the free-ICR law alike; a subclass takes
    the rest in :meth:`_configure`.
    """

    __slots__ = ()

    @property
    def config(self) -> DlsmcConfig:
        """
        Return the configuration in use.

        Assigning a new one takes effect at the next step and keeps the loops' state
        (integrals, e(0), adaptive phase).
        """
        return self._config

    @config.setter
    def config(self, config: DlsmcConfig) -> None:
        self._config = config
        self._limits = config.limits
        self._dt = config.dt
        self._omega_tau = config.omega_filter  # [s] low-pass of the commanded omega (0: none)
        self._omega_band = config.omega_filter_band  # [rad] abs(s) where it has faded
        self.outer.gains = config.outer_in_use
        self.inner.gains = config.inner_in_use
        self.inner.omega_max = config.limits.omega_max
        self._configure(config)

    def _configure(self, config: DlsmcConfig) -> None:
        """Take what only this controller uses of ``config`` (nothing here)."""


class DlsmcController(DlsmcLoops, CascadeController):
    """
    The DLSMC: the cascade of Fig. 2 with the BTINTSMC and the ABFSMC.

    The :class:`~nfmr_dlsmc.core.cascade.CascadeController` with the BTINTSMC position loop
    (eqs 32-35) and the ABFSMC attitude loop (eqs 10-13), stepped once per control period
    ``config.dt``.

    Attributes (after a step): those of the cascade, and
    ``outer``, ``inner`` : BtintsmcOuterLoop, AbfsmcInnerLoop with their own step
    attributes (s_x, s_y, eta_hat, phase, ...).
    """

    #: Names of the values :meth:`telemetry` returns, in order.
    TELEMETRY_FIELDS = ('x_e', 'y_e', 'theta_d', 'thetadot_d', 'theta_e', 's_x', 's_y',
                        'eta_hat', 'inner_phase', 'v_raw', 'omega_raw', 'v_saturated',
                        'omega_saturated')

    __slots__ = ('_config',)

    def __init__(self, config: DlsmcConfig | None = None):
        config = DlsmcConfig() if config is None else config
        super().__init__(BtintsmcOuterLoop(config.outer_in_use),
                         AbfsmcInnerLoop(config.inner_in_use), name='dlsmc')
        self.config = config

    def _configure(self, config: DlsmcConfig) -> None:
        """Take the cascade's own options: theta_d's filter and source, align_speed."""
        self._filter_tau = config.thetadot_filter
        self._align = config.align_speed
        self._analytic = config.thetadot_source == 'analytic'

    def telemetry(self) -> tuple:
        """Return the internal signals of the last step, named by ``TELEMETRY_FIELDS``."""
        return (self.x_e, self.y_e, self.theta_d, self.thetadot_d, self.s_theta,
                self.outer.s_x, self.outer.s_y, self.inner.eta_hat, self.inner.phase,
                self.v_raw, self.omega_raw, self.v_saturated, self.omega_saturated)
