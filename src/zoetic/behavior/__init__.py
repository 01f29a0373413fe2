"""What an animal does with what it learned: repertoires, tracking, macro controllers."""
