"""What runs many scenarios: data collection (``collect``, its teachers and sampler), the
closed-loop timing benchmark (``bench``) and the paper's tables and figures
(``reproduce``). Above the controllers and the scenario runner; nothing below imports it."""
