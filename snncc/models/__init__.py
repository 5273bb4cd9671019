"""snncc's model zoo: the paper's RSNN/FFSNN (CUBA LIF) and LSTM/eLSTM as torch modules."""

from snncc.models.lstm import LSTMClassifier, LSTMConfig, count_trainable
from snncc.models.snn import UPDATE_ORDERS, SNNConfig, SpikingClassifier

__all__ = ["SpikingClassifier", "SNNConfig", "UPDATE_ORDERS", "LSTMClassifier", "LSTMConfig", "count_trainable"]
