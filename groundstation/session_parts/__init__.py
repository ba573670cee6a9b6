"""What a session is built of, below the product and its makers: the tables (``table``) and what they
hold (``catalogue``), session time (``clock``), link health (``link``), the host estimators (``estimators``)
and the aiding sensors (``aiding``) they are fed, and the figures a session is summed up by (``figures``).
"""
