"""Small building blocks shared by the encoders and heads."""

from torch import nn


def mlp(in_ch, hidden, out_ch, act=nn.ReLU, final_act=False):
    """Linear, act, ..., Linear: the Linear layers are named 0, 2, 4, ..."""
    layers, c = [], in_ch
    for h in hidden:
        layers += [nn.Linear(c, h), act()]
        c = h
    layers.append(nn.Linear(c, out_ch))
    if final_act:
        layers.append(act())
    return nn.Sequential(*layers)
