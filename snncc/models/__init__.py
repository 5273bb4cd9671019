"""snncc's model zoo: the paper's RSNN/FFSNN (CUBA LIF), LSTM/eLSTM and the buffered time-series
classifiers (FCN, ResNet, Encoder, Time-CNN, Inception) as torch modules."""

from snncc.models.baselines import BASELINE_KINDS, BaselineConfig, BufferedClassifier
from snncc.models.lstm import LSTMClassifier, LSTMConfig, count_trainable
from snncc.models.snn import UPDATE_ORDERS, SNNConfig, SpikingClassifier

__all__ = ["SpikingClassifier", "SNNConfig", "UPDATE_ORDERS", "LSTMClassifier", "LSTMConfig", "count_trainable",
           "BufferedClassifier", "BaselineConfig", "BASELINE_KINDS"]
