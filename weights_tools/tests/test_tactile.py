import pytest
import torch
import torch.nn.functional as F
import torchvision.transforms.functional as TF

from weights_tools.tactile import IMAGENET_MEAN, IMAGENET_STD, center_crop, crop_start, preprocess


@pytest.mark.parametrize("h,w,crop", [
    (120, 160, 128), (240, 320, 320), (480, 640, 320), (121, 163, 64),
    (7, 9, 8), (67, 69, 64), (65, 66, 64), (64, 64, 64), (3, 200, 10),
])
def test_center_crop_matches_torchvision(h, w, crop):
    x = torch.rand(3, h, w, generator=torch.Generator().manual_seed(h * w))
    assert torch.equal(center_crop(x, crop), TF.center_crop(x, [crop, crop]))


def test_crop_start_rounds_half_to_even():
    # (67 - 64) / 2 = 1.5 -> 2 ; (69 - 64) / 2 = 2.5 -> 2 (Python round, as torchvision)
    assert crop_start(67, 64) == 2 and crop_start(69, 64) == 2
    assert crop_start(240, 320) == -40 and crop_start(63, 64) == 0


def test_preprocess_white_image():
    img = torch.full((50, 70, 3), 255, dtype=torch.uint8)
    x = preprocess(img, crop=50, in_size=25)
    for c in range(3):
        assert torch.allclose(x[0, c], torch.tensor((1 - IMAGENET_MEAN[c]) / IMAGENET_STD[c]))


def test_preprocess_pipeline():
    g = torch.Generator().manual_seed(0)
    img = torch.randint(0, 256, (120, 160, 3), dtype=torch.uint8, generator=g)
    x = preprocess(img, crop=128, in_size=40)
    ref = TF.center_crop(img.permute(2, 0, 1).float() / 255, [128, 128])[None]
    ref = F.interpolate(ref, size=(40, 40), mode="bilinear", align_corners=False, antialias=False)
    ref = TF.normalize(ref, IMAGENET_MEAN, IMAGENET_STD)
    assert x.shape == (1, 3, 40, 40)
    assert torch.allclose(x, ref, atol=1e-6)
    # zero padded rows (120 < 128) become -mean/std after normalisation
    y = preprocess(img, crop=128, in_size=128)
    assert torch.allclose(y[0, 0, 0], torch.tensor(-IMAGENET_MEAN[0] / IMAGENET_STD[0]))
