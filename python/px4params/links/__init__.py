"""Links to the vehicle's peers: the MAVLink parameter server (``mavlink``) and DroneCAN CAN
transfers (``can_transfer``)."""
